//! `report.md`: the study's settings, a table of results per configuration and one of the
//! error estimate against the truth, and the plots beside it.

use std::fmt::Write as _;
use std::path::Path;

use super::error::{file_err, ConvergeError};
use super::metrics::fit_loglog;
use super::options::ladder;
use super::plots::plot;
use super::results::{curve, to_reach, Reach, Study, MAX_EXTRAPOLATION, TARGETS};

fn fmt_amount(x: f64) -> String {
    if x >= 100.0 {
        format!("{x:.0}")
    } else if x >= 10.0 {
        format!("{x:.1}")
    } else {
        format!("{x:.2}")
    }
}

/// Writes `report.md` and the two plots for a study.
pub fn write_report(study: &Study, out: &Path) -> Result<(), ConvergeError> {
    let mut md = String::new();
    let r = &study.reference;
    let _ = writeln!(
        md,
        "## {}\n\nWritten on {} by `wgtrace converge`.\n",
        study.scene_name(),
        crate::report::today()
    );
    let _ = writeln!(
        md,
        "{}x{} pixels, max_depth {} (scene), device: {}. Reference: {} spp ({} / {}, max_depth {}, seed {:#x}, {:.0} s on {}; its own estimated relMSE {:.1e}).\n",
        study.width,
        study.height,
        study.max_depth,
        study.device,
        r.spp,
        r.sampler,
        r.light_sampling,
        r.max_depth,
        r.seed,
        r.seconds,
        r.backend,
        r.est_rel_mse
    );
    let _ = writeln!(
        md,
        "Slope: least-squares fit of log RMSE against log spp over the ladder (-0.5 is plain Monte Carlo). \
         relMSE and seconds at the largest spp are means over runs; efficiency is 1 / (relMSE x seconds). \
         est/true: the renderer's own error estimate (per-pixel variance, what `--target-error` uses) over the true relMSE. \
         Time and spp to reach each relMSE are interpolated between measured points; `~` marks an extrapolation along the fitted slope \
         (at most {MAX_EXTRAPOLATION}x the largest spp, `>` beyond), `never` a curve that has levelled off over its last three points (bias).\n"
    );
    md += &results_table(study);
    let _ = writeln!(
        md,
        "\n![RMSE against samples per pixel](rmse_vs_spp.svg)\n![RMSE against seconds](rmse_vs_seconds.svg)\n"
    );
    md += &estimate_table(study);
    let path = out.join("report.md");
    std::fs::write(&path, md).map_err(|e| file_err(&path, e))?;
    plot(study, out, false)?;
    plot(study, out, true)?;
    Ok(())
}

/// The report's table of results: a row per configuration at its largest spp, with the
/// samples and seconds it needs for each relMSE of [`TARGETS`].
fn results_table(study: &Study) -> String {
    let mut md = String::new();
    let mut header =
        "| configuration | slope | relMSE | seconds | Msamples/s | efficiency | est/true |"
            .to_string();
    let mut rule = "|---|---|---|---|---|---|---|".to_string();
    for t in TARGETS {
        let _ = write!(header, " to {t:.0e}: spp, s |");
        rule += "---|";
    }
    let _ = writeln!(md, "{header}\n{rule}");
    for label in study.labels() {
        let pts = curve(study, &label);
        let Some(last) = pts.last() else { continue };
        let slope = fit_loglog(
            &pts.iter()
                .map(|m| (f64::from(m.spp), m.rmse))
                .collect::<Vec<_>>(),
        )
        .map_or("-".to_string(), |(s, _)| format!("{s:.2}"));
        let est = last.est_rel_mse / last.rel_mse;
        let mut row = format!(
            "| {label} | {slope} | {:.2e} | {:.2} | {:.3} | {:.3e} | {} |",
            last.rel_mse,
            last.seconds,
            last.msamples_per_s,
            last.efficiency,
            if est.is_nan() {
                "-".to_string()
            } else {
                format!("{est:.2}")
            }
        );
        for t in TARGETS {
            let cell = match to_reach(&pts, t) {
                Reach::Measured { spp, seconds } => {
                    format!(" {}, {} |", fmt_amount(spp), fmt_amount(seconds))
                }
                Reach::Extrapolated { spp, seconds } => {
                    format!(" ~{}, ~{} |", fmt_amount(spp), fmt_amount(seconds))
                }
                Reach::Beyond { spp } => format!(" > {} spp |", fmt_amount(spp)),
                Reach::Never => " never |".to_string(),
            };
            row += &cell;
        }
        let _ = writeln!(md, "{row}");
    }
    md
}

/// The report's table of the error estimate `--target-error` stops on, against the truth,
/// along the ladder.
fn estimate_table(study: &Study) -> String {
    let mut md = String::new();
    let spps: Vec<u32> = ladder(study.measurements.iter().map(|m| m.spp).max().unwrap_or(1))
        .into_iter()
        .filter(|s| s.is_power_of_two() && *s >= 4 && s.trailing_zeros() % 2 == 0)
        .collect();
    let _ = writeln!(
        md,
        "### The error estimate against the truth\n\n\
         Estimated relative error (the square root of the per-pixel variance estimate, what \
         `--target-error` stops on) over the true relative error (the square root of relMSE \
         against the reference), means over runs. 1 is exact; above 1 the estimate is \
         conservative.\n"
    );
    let mut header = "| configuration |".to_string();
    let mut rule = "|---|".to_string();
    for spp in &spps {
        let _ = write!(header, " {spp} spp |");
        rule += "---|";
    }
    let _ = writeln!(md, "{header}\n{rule}");
    for label in study.configs.iter().map(|c| c.label()) {
        let pts = curve(study, &label);
        let mut row = format!("| {label} |");
        for spp in &spps {
            match pts.iter().find(|m| m.spp == *spp) {
                Some(m) if !m.est_rel_mse.is_nan() => {
                    let _ = write!(row, " {:.2} |", (m.est_rel_mse / m.rel_mse).sqrt());
                }
                _ => row += " - |",
            }
        }
        let _ = writeln!(md, "{row}");
    }
    md
}
