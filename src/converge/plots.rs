//! The study's plots: RMSE against samples and against seconds, log-log (plotters, SVG).

use std::path::Path;

use super::error::{file_err, ConvergeError};
use super::results::{curve, Study};

/// RMSE against spp (or seconds), log-log, a line per configuration and the ideal
/// N^-1/2 through the first configuration's first point.
pub(super) fn plot(study: &Study, out: &Path, by_time: bool) -> Result<(), ConvergeError> {
    use plotters::prelude::*;
    let name = if by_time {
        "rmse_vs_seconds.svg"
    } else {
        "rmse_vs_spp.svg"
    };
    let path = out.join(name);
    let curves: Vec<(String, Vec<(f64, f64)>)> = study
        .labels()
        .into_iter()
        .map(|label| {
            let pts = curve(study, &label);
            let xy = pts
                .iter()
                .map(|m| {
                    let x = if by_time { m.seconds } else { f64::from(m.spp) };
                    (x.max(1e-6), m.rmse.max(1e-12))
                })
                .collect();
            (label, xy)
        })
        .filter(|(_, xy): &(String, Vec<(f64, f64)>)| !xy.is_empty())
        .collect();
    if curves.is_empty() {
        return Ok(());
    }
    let all = curves.iter().flat_map(|(_, xy)| xy.iter().copied());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
    for (x, y) in all {
        x0 = x0.min(x);
        x1 = x1.max(x);
        y0 = y0.min(y);
        y1 = y1.max(y);
    }
    let (x1, y0, y1) = (x1.max(x0 * 2.0), y0 / 1.5, y1 * 1.5);
    let draw = || -> Result<(), Box<dyn std::error::Error>> {
        let root = SVGBackend::new(&path, (900, 600)).into_drawing_area();
        root.fill(&WHITE)?;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                format!(
                    "{}: RMSE against {}",
                    study.scene_name(),
                    if by_time {
                        "seconds"
                    } else {
                        "samples per pixel"
                    }
                ),
                ("sans-serif", 20),
            )
            .margin(12)
            .x_label_area_size(40)
            .y_label_area_size(70)
            .build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
        chart
            .configure_mesh()
            .x_desc(if by_time {
                "seconds"
            } else {
                "samples per pixel"
            })
            .y_desc("RMSE")
            .x_label_formatter(&|v| tick(*v))
            .y_label_formatter(&|v| tick(*v))
            .draw()?;
        for (i, (label, xy)) in curves.iter().enumerate() {
            let color = Palette99::pick(i).stroke_width(2);
            chart
                .draw_series(LineSeries::new(xy.iter().copied(), color))?
                .label(label.as_str())
                .legend(move |(x, y)| {
                    PathElement::new(
                        vec![(x, y), (x + 18, y)],
                        Palette99::pick(i).stroke_width(2),
                    )
                });
        }
        let (fx, fy) = curves[0].1[0];
        let ideal = [(fx, fy), (x1, fy * (x1 / fx).powf(-0.5))];
        chart
            .draw_series(LineSeries::new(ideal, BLACK.stroke_width(1)))?
            .label("ideal N^-1/2")
            .legend(|(x, y)| PathElement::new(vec![(x, y), (x + 18, y)], BLACK));
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::LowerLeft)
            .draw()?;
        root.present()?;
        Ok(())
    };
    draw().map_err(|e| file_err(&path, e))
}

/// An axis label: 3 significant digits, no float noise.
fn tick(v: f64) -> String {
    if v == 0.0 || (1e-2..1e4).contains(&v.abs()) {
        let s = format!("{v:.3}");
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        format!("{v:.1e}")
    }
}
