//! Error metrics and fits on plain numbers: RMSE, relative MSE, efficiency, the log-log
//! line through a curve and where it crosses a level (checked on synthetic data by
//! tests/converge.rs).

use crate::accumulation::REL_MSE_EPSILON;

/// Root mean squared error over every channel of every pixel (linear RGB, same layout).
pub fn rmse(x: &[f32], reference: &[f32]) -> f64 {
    assert_eq!(x.len(), reference.len());
    let sum: f64 = x
        .iter()
        .zip(reference)
        .map(|(&a, &r)| (f64::from(a) - f64::from(r)).powi(2))
        .sum();
    (sum / x.len().max(1) as f64).sqrt()
}

/// Relative MSE, mean((x - r)^2 / (r^2 + 0.01)) over every channel of every pixel.
pub fn rel_mse(x: &[f32], reference: &[f32]) -> f64 {
    assert_eq!(x.len(), reference.len());
    let sum: f64 = x
        .iter()
        .zip(reference)
        .map(|(&a, &r)| {
            let (a, r) = (f64::from(a), f64::from(r));
            (a - r).powi(2) / (r * r + REL_MSE_EPSILON)
        })
        .sum();
    sum / x.len().max(1) as f64
}

/// Efficiency of a render: 1 / (relative MSE x seconds). Doubling the samples of an
/// unbiased Monte Carlo estimator halves the MSE and doubles the time, so this stays
/// constant along a convergence curve of slope -1 in MSE; higher is better.
pub fn efficiency(rel_mse: f64, seconds: f64) -> f64 {
    1.0 / (rel_mse * seconds).max(f64::MIN_POSITIVE)
}

/// Least-squares line through (log x, log y): (slope, intercept). None for fewer than two
/// points with positive coordinates or all x equal.
pub fn fit_loglog(points: &[(f64, f64)]) -> Option<(f64, f64)> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    let n = logs.len() as f64;
    if logs.len() < 2 {
        return None;
    }
    let (mx, my) = (
        logs.iter().map(|p| p.0).sum::<f64>() / n,
        logs.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let slope = sxy / sxx;
    Some((slope, my - slope * mx))
}

/// Where a curve of (x, error) points, x increasing, first gets down to `target`:
/// interpolated linearly in log-log between the two points around the crossing; the first
/// x when it starts below. None when it never does.
pub fn first_crossing(points: &[(f64, f64)], target: f64) -> Option<f64> {
    let first = points.first()?;
    if first.1 <= target {
        return Some(first.0);
    }
    points.windows(2).find_map(|w| {
        let ((x0, e0), (x1, e1)) = (w[0], w[1]);
        (e1 <= target).then(|| {
            let t = (target.ln() - e0.ln()) / (e1.ln() - e0.ln());
            (x0.ln() + t * (x1.ln() - x0.ln())).exp()
        })
    })
}
