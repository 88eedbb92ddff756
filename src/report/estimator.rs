//! The estimators a report compares, and their names on the command line.

/// One way to estimate the derivative image (or, for [`Estimator::Primal`], the image itself).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Estimator {
    /// Interior + primary + secondary boundary terms with the default boundary budgets.
    Complete,
    /// The interior term alone: biased wherever a silhouette or a shadow edge moves.
    Interior,
    /// The complete derivative with 4 times the default boundary budgets.
    CompleteBoundaryX4,
    /// The complete derivative with a quarter of the default boundary budgets.
    CompleteBoundaryDiv4,
    /// Central finite differences with common random numbers at the default step.
    Fd,
    /// The primal image (error against a long render), to show how fast the image converges.
    Primal,
}

impl Estimator {
    /// Every estimator, in the order of the report's tables and legends.
    pub const ALL: [Estimator; 6] = [
        Estimator::Complete,
        Estimator::Interior,
        Estimator::CompleteBoundaryX4,
        Estimator::CompleteBoundaryDiv4,
        Estimator::Fd,
        Estimator::Primal,
    ];

    /// The name used by `--estimators`, the CSV and the legend.
    pub fn name(self) -> &'static str {
        match self {
            Estimator::Complete => "complete",
            Estimator::Interior => "interior",
            Estimator::CompleteBoundaryX4 => "complete-boundary-x4",
            Estimator::CompleteBoundaryDiv4 => "complete-boundary-div4",
            Estimator::Fd => "fd",
            Estimator::Primal => "primal",
        }
    }

    /// Whether it estimates a derivative (every estimator but [`Estimator::Primal`]).
    pub fn is_derivative(self) -> bool {
        self != Estimator::Primal
    }

    /// The boundary budgets as a fraction `(numerator, denominator)` of the default ones, for the
    /// estimators that sample boundary terms; `None` for the others.
    pub fn boundary_scale(self) -> Option<(u64, u64)> {
        match self {
            Estimator::Complete => Some((1, 1)),
            Estimator::CompleteBoundaryX4 => Some((4, 1)),
            Estimator::CompleteBoundaryDiv4 => Some((1, 4)),
            Estimator::Interior | Estimator::Fd | Estimator::Primal => None,
        }
    }

    /// Parses a comma-separated list of names (duplicates kept once, in the order given); the error
    /// is one line naming the unknown entry and the known names.
    pub fn parse_list(text: &str) -> Result<Vec<Estimator>, String> {
        let mut list = Vec::new();
        for name in text.split(',').map(str::trim) {
            let e = (Estimator::ALL.into_iter().find(|e| e.name() == name)).ok_or_else(|| {
                let known: Vec<&str> = Estimator::ALL.iter().map(|e| e.name()).collect();
                format!(
                    "estimators: unknown estimator {name:?} (known: {})",
                    known.join(", ")
                )
            })?;
            if !list.contains(&e) {
                list.push(e);
            }
        }
        Ok(list)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_unknown_names_are_named() {
        let all: Vec<&str> = Estimator::ALL.iter().map(|e| e.name()).collect();
        assert_eq!(
            Estimator::parse_list(&all.join(",")).unwrap(),
            Estimator::ALL
        );
        assert_eq!(
            Estimator::parse_list("fd, complete,fd").unwrap(),
            [Estimator::Fd, Estimator::Complete]
        );
        let e = Estimator::parse_list("complete,fdd").unwrap_err();
        assert!(
            e.contains("\"fdd\"") && e.starts_with("estimators: "),
            "{e}"
        );
        assert!(Estimator::parse_list("").is_err());
    }
}
