//! `progress.csv`: one row per iteration, the columns [`columns`] names.
//!
//! - `iteration`: the 0-based index;
//! - `loss`: the mean loss over the iteration's views, before its step;
//! - `seconds`: wall time since the first iteration started, less the time spent measuring the shapes
//!   (the columns below) and writing snapshots: seconds of optimisation;
//! - `gradient_norm`: the Euclidean norm of the mean gradient;
//! - `iou`, `chamfer`: how close an optimised grid's shape is to the target scene's shape of the same
//!   name ([`super::metrics::shape_quality`]); named `iou.SHAPE`, `chamfer.SHAPE` when several shapes
//!   are compared, absent when none is (targets given as images);
//! - `mesh_chamfer`, `mesh_normal_consistency`, `mesh_iou`: with `reference_mesh`, the optimised
//!   shapes' mesh against it ([`super::metrics::mesh_quality`]: the Chamfer distance as a fraction of
//!   the reference's bounding-box diagonal, the mean `|n·n'|` of nearest points, the IoU of the
//!   insides); absent without;
//! - `loss_pass_seconds` ... `grid_edit_seconds`: where the iteration's time went ([`StageSeconds`]).

use super::StageSeconds;

/// The columns of the measures against a reference mesh.
pub const MESH_COLUMNS: [&str; 3] = ["mesh_chamfer", "mesh_normal_consistency", "mesh_iou"];

/// One row of `progress.csv`: a finished iteration.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// 0-based index.
    pub iteration: u32,
    /// Mean loss over the iteration's views (before the step).
    pub loss: f64,
    /// Wall-clock seconds since the first iteration started, at the end of this one, less the time
    /// spent measuring shapes and writing snapshots before it.
    pub seconds: f64,
    /// Euclidean norm of the mean gradient.
    pub gradient_norm: f64,
    /// `(IoU, Chamfer distance)` of each compared shape, in the order of the columns (NaN when the
    /// shape cannot be measured).
    pub shapes: Vec<(f64, f64)>,
    /// The measures against the reference mesh, when there is one.
    pub mesh: Option<crate::mesh::metrics::MeshMetrics>,
    /// Where the iteration's time went.
    pub stage_seconds: StageSeconds,
}

/// The columns of `progress.csv` when the shapes `compared` are measured against the target scene,
/// and the optimised shapes against a reference mesh if `mesh`.
pub fn columns(compared: &[String], mesh: bool) -> Vec<String> {
    let mut out: Vec<String> = ["iteration", "loss", "seconds", "gradient_norm"]
        .map(String::from)
        .into();
    for name in compared {
        if compared.len() == 1 {
            out.extend(["iou".to_string(), "chamfer".to_string()]);
        } else {
            out.extend([format!("iou.{name}"), format!("chamfer.{name}")]);
        }
    }
    if mesh {
        out.extend(MESH_COLUMNS.map(String::from));
    }
    out.extend(
        [
            "loss_pass_seconds",
            "interior_seconds",
            "primary_seconds",
            "secondary_seconds",
            "grid_edit_seconds",
        ]
        .map(String::from),
    );
    out
}

impl Row {
    /// The row's values in the order of [`columns`] (the iteration as a float).
    pub fn values(&self) -> Vec<f64> {
        let t = &self.stage_seconds;
        let mut out = vec![
            self.iteration as f64,
            self.loss,
            self.seconds,
            self.gradient_norm,
        ];
        for &(iou, chamfer) in &self.shapes {
            out.extend([iou, chamfer]);
        }
        if let Some(m) = &self.mesh {
            out.extend([m.chamfer, m.normal_consistency, m.iou]);
        }
        out.extend([
            t.loss_pass,
            t.interior,
            t.primary,
            t.secondary,
            t.grid_edits,
        ]);
        out
    }

    /// The row as a line of `progress.csv` (without the newline): every number in Rust's shortest
    /// form that reads back to the same `f64`.
    pub fn csv(&self) -> String {
        let t = &self.stage_seconds;
        let mut row = format!(
            "{},{},{},{}",
            self.iteration, self.loss, self.seconds, self.gradient_norm
        );
        for (iou, chamfer) in &self.shapes {
            row += &format!(",{iou},{chamfer}");
        }
        if let Some(m) = &self.mesh {
            row += &format!(",{},{},{}", m.chamfer, m.normal_consistency, m.iou);
        }
        row += &format!(
            ",{},{},{},{},{}",
            t.loss_pass, t.interior, t.primary, t.secondary, t.grid_edits
        );
        row
    }

    /// The IoU of the first compared shape (what a progress display shows), if any is compared.
    pub fn iou(&self) -> Option<f64> {
        self.shapes.first().map(|s| s.0)
    }
}

/// The columns `names` of every row of a `progress.csv` written by [`Row::csv`], row by row (for the
/// figures drawn from finished runs). Errors name the file and the missing column or unreadable row.
pub fn read_columns(path: &std::path::Path, names: &[&str]) -> crate::error::Result<Vec<Vec<f64>>> {
    use crate::error::Error;
    let text = std::fs::read_to_string(path).map_err(|e| Error::file(path, e))?;
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap_or("").split(',').collect();
    let columns = (names.iter())
        .map(|name| {
            (header.iter().position(|h| h == name))
                .ok_or_else(|| Error::file(path, format!("no column {name:?}")))
        })
        .collect::<crate::error::Result<Vec<usize>>>()?;
    let mut rows = Vec::new();
    for (k, line) in lines.enumerate() {
        let cells: Vec<&str> = line.split(',').collect();
        let row = (columns.iter())
            .map(|&c| cells.get(c).and_then(|cell| cell.parse::<f64>().ok()))
            .collect::<Option<Vec<f64>>>()
            .ok_or_else(|| {
                Error::file(path, format!("row {}: not {} numbers", k + 2, names.len()))
            })?;
        rows.push(row);
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_read_back_as_written() {
        let rows: Vec<Row> = (0..3)
            .map(|i| Row {
                iteration: i,
                loss: 0.1 / (i + 1) as f64,
                seconds: 1.5 * i as f64,
                gradient_norm: 2.0,
                shapes: vec![(0.5 + 0.1 * i as f64, 0.01)],
                mesh: None,
                stage_seconds: StageSeconds::default(),
            })
            .collect();
        let dir = std::env::temp_dir().join(format!("progress-read-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("progress.csv");
        let mut text = columns(&["shape".into()], false).join(",") + "\n";
        for row in &rows {
            text += &(row.csv() + "\n");
        }
        std::fs::write(&path, text).unwrap();
        let read = read_columns(&path, &["seconds", "iou"]).unwrap();
        let expected: Vec<Vec<f64>> = rows
            .iter()
            .map(|r| vec![r.seconds, r.shapes[0].0])
            .collect();
        assert_eq!(read, expected);
        let missing = read_columns(&path, &["mesh_iou"]).unwrap_err().to_string();
        assert!(missing.contains("mesh_iou"), "{missing}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
