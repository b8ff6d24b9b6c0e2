//! The convergence chart `caustica converge` writes: error against time on log-log axes, one
//! colour per run, the true relMSE solid and the estimated relMSE dashed (plotters, drawn into
//! memory and saved with the `image` crate, with egui's own font so no system font is needed).

use super::record::Record;
use plotters::prelude::*;
use std::path::Path;
use std::sync::Once;

const SIZE: (u32, u32) = (960, 640);

fn register_font() {
    static FONT: Once = Once::new();
    FONT.call_once(|| {
        // The bytes are a valid TrueType font shipped with egui; failing leaves the labels out.
        let _ = plotters::style::register_font(
            "sans-serif",
            FontStyle::Normal,
            epaint_default_fonts::UBUNTU_LIGHT,
        );
    });
}

/// Log-spaced bounds that contain every positive value (a decade around a single value).
fn log_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (lo, hi) = values
        .filter(|v| v.is_finite() && *v > 0.0)
        .fold((f64::INFINITY, 0.0f64), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    (hi > 0.0).then(|| (lo / 1.5, hi * 1.5))
}

pub fn draw_convergence(
    path: &Path,
    title: &str,
    runs: &[Vec<Record>],
    have_reference: bool,
) -> Result<(), String> {
    register_font();
    let records = || runs.iter().flatten();
    let (t0, t1) = log_range(records().map(|r| r.seconds)).ok_or("no records to plot")?;
    let (e0, e1) =
        log_range(records().flat_map(|r| [r.rel_mse, r.estimated_rel_mse].into_iter().flatten()))
            .ok_or("no errors to plot")?;
    let mut buffer = vec![0u8; (SIZE.0 * SIZE.1 * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buffer, SIZE).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 22))
            .margin(12)
            .x_label_area_size(44)
            .y_label_area_size(72)
            .build_cartesian_2d((t0..t1).log_scale(), (e0..e1).log_scale())
            .map_err(|e| e.to_string())?;
        chart
            .configure_mesh()
            .x_desc("seconds")
            .y_desc(if have_reference {
                "relMSE (solid: true, dashed: estimated)"
            } else {
                "estimated relMSE"
            })
            .x_label_formatter(&|v| format!("{v:.3}"))
            .y_label_formatter(&|v| format!("{v:.0e}"))
            .draw()
            .map_err(|e| e.to_string())?;
        for (i, run) in runs.iter().enumerate() {
            let Some(first) = run.first() else { continue };
            let colour = Palette99::pick(i).to_rgba();
            let style = ShapeStyle::from(colour).stroke_width(2);
            let truth: Vec<(f64, f64)> = run
                .iter()
                .filter_map(|r| r.rel_mse.map(|e| (r.seconds, e)))
                .filter(|p| p.1 > 0.0)
                .collect();
            let estimated: Vec<(f64, f64)> = run
                .iter()
                .filter_map(|r| r.estimated_rel_mse.map(|e| (r.seconds, e)))
                .filter(|p| p.1 > 0.0)
                .collect();
            let label = first.run.clone();
            if truth.is_empty() {
                chart
                    .draw_series(DashedLineSeries::new(estimated, 8, 5, style))
                    .map_err(|e| e.to_string())?
                    .label(label)
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], style));
            } else {
                chart
                    .draw_series(LineSeries::new(truth, style))
                    .map_err(|e| e.to_string())?
                    .label(label)
                    .legend(move |(x, y)| PathElement::new([(x, y), (x + 20, y)], style));
                chart
                    .draw_series(DashedLineSeries::new(estimated, 8, 5, style))
                    .map_err(|e| e.to_string())?;
            }
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .position(SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(|e| e.to_string())?;
        root.present().map_err(|e| e.to_string())?;
    }
    let image = image::RgbImage::from_raw(SIZE.0, SIZE.1, buffer).ok_or("bad buffer size")?;
    image.save(path).map_err(|e| e.to_string())
}
