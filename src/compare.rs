//! Comparison of derivative images, e.g. a `diff` result against an `fd` reference: the numbers that
//! `implicit-psdr compare A.exr B.exr` prints for each channel present in both files.
//!
//! `B` is the reference: errors are relative to `‖b‖`. All sums are accumulated in `f64`.

use crate::error::{Error, Result};
use crate::film::{Channels, read_exr};
use std::path::Path;

/// Half-width of the box blur applied before the second error: `2 · 2 + 1 = 5` pixels, a 5×5 box.
pub const BLUR_RADIUS: usize = 2;

/// The comparison of one channel of `A` with the same channel of the reference `B`.
#[derive(Clone, Debug, PartialEq)]
pub struct ChannelComparison {
    /// Channel name (`d.ball.radius.R`, ...).
    pub name: String,
    /// [`relative_l2`] of the raw values.
    pub relative_l2: f64,
    /// [`relative_l2`] after a 5×5 [`box_blur`] of both images (pixel noise averaged out; what remains is
    /// bias, or noise correlated over several pixels).
    pub relative_l2_blurred: f64,
    /// `Σ a`.
    pub sum_a: f64,
    /// `Σ b`.
    pub sum_b: f64,
    /// `Σ |a|`.
    pub abs_sum_a: f64,
    /// `Σ |b|`.
    pub abs_sum_b: f64,
    /// Pearson [`correlation`] of `a` and `b`; `None` when either is constant.
    pub correlation: Option<f64>,
}

/// `‖a − b‖₂ / ‖b‖₂` (`b` is the reference). When `‖b‖ = 0` it is 0 if `a = b` too, else infinite.
pub fn relative_l2(a: &[f32], b: &[f32]) -> f64 {
    assert_eq!(a.len(), b.len(), "relative_l2 of different lengths");
    let (mut diff, mut norm) = (0.0f64, 0.0f64);
    for (&x, &y) in a.iter().zip(b) {
        let (x, y) = (x as f64, y as f64);
        diff += (x - y) * (x - y);
        norm += y * y;
    }
    if norm > 0.0 {
        (diff / norm).sqrt()
    } else if diff == 0.0 {
        0.0
    } else {
        f64::INFINITY
    }
}

/// Box blur of a `width × height` plane (row-major) with a `(2 radius + 1)²` window.
///
/// Edges: the window is clipped to the image and the mean is taken over the pixels inside it (no padding
/// with zeros or mirrored values), so a constant image stays that constant up to the border. The clipped
/// window is still a rectangle, so the blur is done separably (rows, then columns), exactly.
pub fn box_blur(values: &[f32], width: usize, height: usize, radius: usize) -> Vec<f32> {
    assert_eq!(values.len(), width * height, "box_blur: plane size");
    // One axis: mean over [i − radius, i + radius] ∩ [0, n), by a running sum in f64.
    fn blur_line(line: &[f64], radius: usize, out: &mut [f64]) {
        let n = line.len();
        let mut prefix = vec![0.0f64; n + 1];
        for i in 0..n {
            prefix[i + 1] = prefix[i] + line[i];
        }
        for (i, o) in out.iter_mut().enumerate() {
            let lo = i.saturating_sub(radius);
            let hi = (i + radius + 1).min(n);
            *o = (prefix[hi] - prefix[lo]) / (hi - lo) as f64;
        }
    }
    let mut rows = vec![0.0f64; values.len()];
    let mut line = vec![0.0f64; width.max(height)];
    let mut out = vec![0.0f64; width.max(height)];
    for y in 0..height {
        for x in 0..width {
            line[x] = values[y * width + x] as f64;
        }
        blur_line(&line[..width], radius, &mut out[..width]);
        rows[y * width..(y + 1) * width].copy_from_slice(&out[..width]);
    }
    let mut result = vec![0.0f32; values.len()];
    for x in 0..width {
        for y in 0..height {
            line[y] = rows[y * width + x];
        }
        blur_line(&line[..height], radius, &mut out[..height]);
        for y in 0..height {
            result[y * width + x] = out[y] as f32;
        }
    }
    result
}

/// Pearson's correlation coefficient `cov(a, b) / (σ_a σ_b)`; `None` when either has zero variance
/// (e.g. a derivative that is zero everywhere) or the planes are empty.
pub fn correlation(a: &[f32], b: &[f32]) -> Option<f64> {
    assert_eq!(a.len(), b.len(), "correlation of different lengths");
    let n = a.len() as f64;
    if a.is_empty() {
        return None;
    }
    let mean_a = a.iter().map(|&x| x as f64).sum::<f64>() / n;
    let mean_b = b.iter().map(|&x| x as f64).sum::<f64>() / n;
    let (mut cov, mut var_a, mut var_b) = (0.0f64, 0.0f64, 0.0f64);
    for (&x, &y) in a.iter().zip(b) {
        let (dx, dy) = (x as f64 - mean_a, y as f64 - mean_b);
        cov += dx * dy;
        var_a += dx * dx;
        var_b += dy * dy;
    }
    (var_a > 0.0 && var_b > 0.0).then(|| cov / (var_a * var_b).sqrt())
}

/// Every number of a [`ChannelComparison`] for planes `a` and `b` of `width × height` values.
pub fn compare_channel(
    name: &str,
    a: &[f32],
    b: &[f32],
    width: usize,
    height: usize,
) -> ChannelComparison {
    let sum = |v: &[f32]| v.iter().map(|&x| x as f64).sum::<f64>();
    let abs_sum = |v: &[f32]| v.iter().map(|&x| (x as f64).abs()).sum::<f64>();
    ChannelComparison {
        name: name.to_string(),
        relative_l2: relative_l2(a, b),
        relative_l2_blurred: relative_l2(
            &box_blur(a, width, height, BLUR_RADIUS),
            &box_blur(b, width, height, BLUR_RADIUS),
        ),
        sum_a: sum(a),
        sum_b: sum(b),
        abs_sum_a: abs_sum(a),
        abs_sum_b: abs_sum(b),
        correlation: correlation(a, b),
    }
}

/// Names of the channels present in both `a` and `b` that are compared: with no `prefix`, the
/// derivative channels (names starting with `d`: `d.`, `d_interior.`, ...; the image channels `R`, `G`,
/// `B` are skipped); with a `prefix`, exactly the names starting with it. Ordered by name, except that
/// the colour suffixes come as `R`, `G`, `B` (EXR files store channels in byte order: `B`, `G`, `R`).
pub fn select_channels(a: &Channels, b: &Channels, prefix: Option<&str>) -> Vec<String> {
    let mut names: Vec<String> = a
        .iter()
        .map(|(name, _)| name)
        .filter(|name| match prefix {
            Some(p) => name.starts_with(p),
            None => name.starts_with('d'),
        })
        .filter(|name| b.iter().any(|(other, _)| other == *name))
        .cloned()
        .collect();
    // "d.p.G" → ("d.p.", 1): colours of one quantity together, in R, G, B order.
    let key = |name: &String| {
        let (stem, last) = name.rsplit_once('.').unwrap_or(("", name.as_str()));
        let colour = ["R", "G", "B"].iter().position(|c| *c == last);
        (stem.to_string(), colour.unwrap_or(3), last.to_string())
    };
    names.sort_by_key(key);
    names
}

/// Compares the selected channels (see [`select_channels`]) of two images of the same size, `b` being
/// the reference. Errors: different sizes; no channel selected.
pub fn compare_images(
    a: (u32, u32, &Channels),
    b: (u32, u32, &Channels),
    prefix: Option<&str>,
) -> Result<Vec<ChannelComparison>> {
    let ((wa, ha, ca), (wb, hb, cb)) = (a, b);
    if (wa, ha) != (wb, hb) {
        return Err(Error::Unsupported(format!(
            "image sizes differ: {wa}x{ha} and {wb}x{hb}"
        )));
    }
    let names = select_channels(ca, cb, prefix);
    if names.is_empty() {
        let list = |c: &Channels| {
            let names: Vec<&str> = c.iter().map(|(n, _)| n.as_str()).collect();
            if names.is_empty() {
                "none".to_string()
            } else {
                names.join(" ")
            }
        };
        let what = match prefix {
            Some(p) => format!("no channel starting with {p:?}"),
            None => "no derivative channel (name starting with \"d\")".to_string(),
        };
        return Err(Error::Unsupported(format!(
            "{what} in both images (first has: {}; second has: {})",
            list(ca),
            list(cb)
        )));
    }
    let plane = |c: &'_ Channels, name: &str| -> Vec<f32> {
        c.iter()
            .find(|(n, _)| n == name)
            .map(|(_, v)| v.clone())
            .unwrap_or_default()
    };
    Ok(names
        .iter()
        .map(|name| {
            compare_channel(
                name,
                &plane(ca, name),
                &plane(cb, name),
                wa as usize,
                ha as usize,
            )
        })
        .collect())
}

/// Reads two EXR files and compares them with [`compare_images`], `b` being the reference. Errors as
/// there (naming both files), and unreadable files.
pub fn compare_files(a: &Path, b: &Path, prefix: Option<&str>) -> Result<Vec<ChannelComparison>> {
    let (wa, ha, ca) = read_exr(a)?;
    let (wb, hb, cb) = read_exr(b)?;
    compare_images((wa, ha, &ca), (wb, hb, &cb), prefix)
        .map_err(|e| Error::Unsupported(format!("{} vs {}: {e}", a.display(), b.display())))
}

/// The table `compare` prints: one row per channel of `rows`, `a` checked against the reference `b`.
pub fn format_table(a: &Path, b: &Path, rows: &[ChannelComparison]) -> String {
    let width = rows
        .iter()
        .map(|r| r.name.len())
        .max()
        .unwrap_or(0)
        .max("channel".len());
    let mut text = format!(
        "A = {}, B = {} (the reference): rel.err = |A - B| / |B| (L2), blurred after a 5x5 box blur\n",
        a.display(),
        b.display()
    );
    text += &format!(
        "{:<width$}  {:>10}  {:>12}  {:>11}  {:>11}  {:>11}  {:>11}  {:>8}\n",
        "channel", "rel.err", "rel.err.blur", "sum A", "sum B", "sum |A|", "sum |B|", "corr"
    );
    for r in rows {
        let correlation = r
            .correlation
            .map_or_else(|| "n/a".to_string(), |c| format!("{c:.5}"));
        text += &format!(
            "{:<width$}  {:>10.3e}  {:>12.3e}  {:>11.4e}  {:>11.4e}  {:>11.4e}  {:>11.4e}  {:>8}\n",
            r.name,
            r.relative_l2,
            r.relative_l2_blurred,
            r.sum_a,
            r.sum_b,
            r.abs_sum_a,
            r.abs_sum_b,
            correlation
        );
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A deterministic, non-constant plane.
    fn plane(width: usize, height: usize) -> Vec<f32> {
        (0..width * height)
            .map(|i| ((i * 7919) % 101) as f32 / 10.0 - 5.0)
            .collect()
    }

    #[test]
    fn identical_planes() {
        let a = plane(9, 7);
        let c = compare_channel("d.x.R", &a, &a, 9, 7);
        assert_eq!(c.relative_l2, 0.0);
        assert_eq!(c.relative_l2_blurred, 0.0);
        assert!((c.correlation.unwrap() - 1.0).abs() < 1e-12);
        assert_eq!(c.sum_a, c.sum_b);
        assert_eq!(c.abs_sum_a, c.abs_sum_b);
    }

    #[test]
    fn scaled_and_shifted_planes() {
        let b = plane(9, 7);
        let a: Vec<f32> = b.iter().map(|x| 1.25 * x).collect();
        let c = compare_channel("d.x.R", &a, &b, 9, 7);
        // ‖1.25 b − b‖ / ‖b‖ = 0.25 exactly; the blur is linear, so the same after it.
        assert!((c.relative_l2 - 0.25).abs() < 1e-7, "{}", c.relative_l2);
        assert!((c.relative_l2_blurred - 0.25).abs() < 1e-6);
        assert!((c.correlation.unwrap() - 1.0).abs() < 1e-12);
        assert!((c.sum_a - 1.25 * c.sum_b).abs() < 1e-4);
        assert!((c.abs_sum_a - 1.25 * c.abs_sum_b).abs() < 1e-4);
        let negated: Vec<f32> = b.iter().map(|x| 3.0 - x).collect();
        assert!((correlation(&negated, &b).unwrap() + 1.0).abs() < 1e-12);
        // b is the reference: ‖a − b‖ / ‖b‖ with b = 2a is 1/2, not 1.
        let half: Vec<f32> = b.iter().map(|x| 0.5 * x).collect();
        assert!((relative_l2(&half, &b) - 0.5).abs() < 1e-7);
        assert!((relative_l2(&b, &half) - 1.0).abs() < 1e-7);
    }

    #[test]
    fn zero_reference() {
        let zero = vec![0.0f32; 12];
        assert_eq!(relative_l2(&zero, &zero), 0.0);
        assert_eq!(relative_l2(&plane(3, 4), &zero), f64::INFINITY);
        assert_eq!(correlation(&zero, &plane(3, 4)), None);
    }

    #[test]
    fn blur_of_constant_is_constant() {
        let v = vec![2.5f32; 6 * 5];
        for r in [0, 1, 2, 7] {
            let blurred = box_blur(&v, 6, 5, r);
            assert!(blurred.iter().all(|&x| (x - 2.5).abs() < 1e-6), "r = {r}");
        }
    }

    #[test]
    fn blur_means_over_clipped_window() {
        let width = 7;
        let v = plane(width, 6);
        let blurred = box_blur(&v, width, 6, 2);
        // Brute force: the mean over the window clipped to the image.
        for y in 0..6usize {
            for x in 0..width {
                let (mut sum, mut n) = (0.0f64, 0);
                for yy in y.saturating_sub(2)..(y + 3).min(6) {
                    for xx in x.saturating_sub(2)..(x + 3).min(width) {
                        sum += v[yy * width + xx] as f64;
                        n += 1;
                    }
                }
                let expected = (sum / n as f64) as f32;
                assert!(
                    (blurred[y * width + x] - expected).abs() < 1e-5,
                    "({x}, {y})"
                );
            }
        }
        // An impulse in the interior spreads to 1/25 over its 5×5 neighbourhood.
        let mut impulse = vec![0.0f32; 81];
        impulse[4 * 9 + 4] = 25.0;
        let b = box_blur(&impulse, 9, 9, BLUR_RADIUS);
        assert!((b[2 * 9 + 2] - 1.0).abs() < 1e-6 && (b[6 * 9 + 6] - 1.0).abs() < 1e-6);
        assert_eq!(b[9 + 4], 0.0);
        assert!((b.iter().sum::<f32>() - 25.0).abs() < 1e-4);
    }

    fn channels(names: &[&str], n: usize) -> Channels {
        names
            .iter()
            .map(|s| (s.to_string(), vec![1.0; n]))
            .collect()
    }

    #[test]
    fn channel_selection() {
        let a = channels(
            &["B", "G", "R", "d.p.B", "d.p.R", "d_interior.p.R", "d.q.R"],
            4,
        );
        let b = channels(&["B", "G", "R", "d.p.R", "d.p.B", "d_interior.p.R"], 4);
        assert_eq!(
            select_channels(&a, &b, None),
            ["d.p.R", "d.p.B", "d_interior.p.R"]
        );
        assert_eq!(select_channels(&a, &b, Some("d.")), ["d.p.R", "d.p.B"]);
        assert_eq!(select_channels(&a, &b, Some("R")), ["R"]);
        assert_eq!(
            select_channels(&a, &b, Some("")),
            ["R", "G", "B", "d.p.R", "d.p.B", "d_interior.p.R"]
        );
        assert!(select_channels(&a, &b, Some("x")).is_empty());
    }

    #[test]
    fn image_errors() {
        let a = channels(&["R", "d.p.R"], 4);
        let b = channels(&["R", "d.p.R"], 6);
        let e = compare_images((2, 2, &a), (3, 2, &b), None).unwrap_err();
        assert_eq!(e.to_string(), "image sizes differ: 2x2 and 3x2");
        let c = channels(&["R", "G", "B"], 4);
        let e = compare_images((2, 2, &a), (2, 2, &c), None).unwrap_err();
        assert!(e.to_string().starts_with("no derivative channel"), "{e}");
        let ok = compare_images((2, 2, &a), (2, 2, &a), None).unwrap();
        assert_eq!(ok.len(), 1);
        assert_eq!(ok[0].relative_l2, 0.0);
    }
}
