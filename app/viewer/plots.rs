//! The plot panel (egui_plot): error against time on log-log axes while a reference is
//! loaded. Axes show log10 values; the tick labels give the plain numbers.

use crate::viewer::app::Command;
use crate::viewer::convergence::Convergence;
use eframe::egui;
use egui_plot::{Legend, Line, Plot, PlotPoints};

fn power_of_ten(mark: egui_plot::GridMark, _range: &std::ops::RangeInclusive<f64>) -> String {
    let v = 10f64.powf(mark.value);
    if (1e-2..1e4).contains(&v) {
        format!("{v:.3}")
            .trim_end_matches('0')
            .trim_end_matches('.')
            .to_string()
    } else {
        format!("{v:.0e}")
    }
}

pub fn plots_panel(ui: &mut egui::Ui, convergence: &Convergence) -> Vec<Command> {
    let mut out = Vec::new();
    ui.horizontal(|ui| {
        ui.strong("Convergence");
        match &convergence.reference {
            Some(path) => {
                ui.label(format!("against {}", path.display()));
            }
            None => {
                ui.label("load a reference EXR to plot the error against time");
            }
        }
        if ui.button("Load reference…").clicked() {
            out.push(Command::ShowReferenceDialog);
        }
        if let Some(p) = &convergence.problem {
            ui.colored_label(ui.visuals().error_fg_color, p);
        }
        if let Some(last) = convergence.points.last() {
            ui.label(format!(
                "relMSE {:.3e} · RMSE {:.3e} · mean luminance ratio {:.4}",
                last.metrics.rel_mse, last.metrics.rmse, last.metrics.mean_luminance_ratio
            ));
        }
    });
    let log_points = |f: fn(&caustica_renderer::image::ErrorMetrics) -> f64| -> PlotPoints {
        convergence
            .points
            .iter()
            .filter(|p| f(&p.metrics) > 0.0)
            .map(|p| [p.seconds.log10(), f(&p.metrics).log10()])
            .collect()
    };
    Plot::new("convergence")
        .legend(Legend::default())
        .x_axis_label("seconds")
        .y_axis_label("error")
        .x_axis_formatter(power_of_ten)
        .y_axis_formatter(power_of_ten)
        .show(ui, |plot| {
            plot.line(Line::new("relMSE", log_points(|m| m.rel_mse)));
            plot.line(Line::new("RMSE", log_points(|m| m.rmse)));
        });
    out
}
