//! The plot panel (egui_plot): error against time on log-log axes, the estimated relMSE
//! always and the true relMSE and RMSE while a reference is loaded. Axes show log10 values;
//! the tick labels give the plain numbers.

use crate::viewer::command::Command;
use crate::viewer::convergence::Convergence;
use caustica_renderer::integrators::{PlotKind, PlotSeries};
use eframe::egui;
use egui_plot::{Bar, BarChart, Legend, Line, Plot, PlotPoints};

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

/// The convergence plot, then every plot the integrator offers, side by side.
pub fn plots_panel(
    ui: &mut egui::Ui,
    convergence: &Convergence,
    integrator_plots: &[PlotSeries],
) -> Vec<Command> {
    let mut out = Vec::new();
    ui.horizontal(|ui| {
        ui.strong("Convergence");
        match &convergence.reference {
            Some(path) => {
                ui.label(format!("against {}", path.display()));
            }
            None => {
                ui.label("estimated error; load a reference EXR for the true error");
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
    let log_points =
        |f: fn(&caustica_renderer::image::ErrorMetrics) -> f64| -> PlotPoints<'static> {
            convergence
                .points
                .iter()
                .filter(|p| f(&p.metrics) > 0.0)
                .map(|p| [p.seconds.log10(), f(&p.metrics).log10()])
                .collect()
        };
    let mut titles: Vec<&str> = Vec::new();
    for series in integrator_plots {
        if !titles.contains(&series.plot.as_str()) {
            titles.push(&series.plot);
        }
    }
    // Each plot takes the height its column has left below its own headers, so the plots
    // never ask for more than the panel has (a panel grows to fit what it holds).
    let columns = 1 + titles.len();
    let width = (ui.available_width() - 8.0 * (columns - 1) as f32) / columns as f32;
    ui.horizontal_top(|ui| {
        ui.vertical(|ui| {
            ui.set_width(width);
            let estimated: PlotPoints<'static> = convergence
                .estimated
                .iter()
                .map(|p| [p[0].log10(), p[1].log10()])
                .collect();
            convergence_plot(ui, &log_points, estimated);
        });
        for title in &titles {
            ui.vertical(|ui| {
                ui.set_width(width);
                ui.strong(*title);
                integrator_plot(ui, title, integrator_plots);
            });
        }
    });
    out
}

/// The height left in `ui` for a plot, at least a legible minimum.
/// A plot drawn cheaply under software rendering: no background fill (the panel's colour
/// shows through) and no grid lines closer than 24 points, the faint ones that fade in
/// between. Every pixel egui's shader fills costs about 40 ns there (see `App::clear_color`
/// in app.rs), and the fill and the fine grid of a plot across the window were a third of
/// a frame.
fn cheap_plot<'a>(id: impl egui::AsIdSalt) -> Plot<'a> {
    Plot::new(id)
        .show_background(false)
        .grid_spacing(24.0..=300.0)
}

fn plot_height(ui: &egui::Ui) -> f32 {
    ui.available_height().max(60.0)
}

fn integrator_plot(ui: &mut egui::Ui, title: &str, all: &[PlotSeries]) {
    let mut series: Vec<&PlotSeries> = all.iter().filter(|s| s.plot == title).collect();
    // Several bar series (MMLT's technique shares, one per path length) overlap: show the
    // one the user picks, remembered in egui's memory for this plot.
    let bars: Vec<&PlotSeries> = series
        .iter()
        .copied()
        .filter(|s| s.kind == PlotKind::Bars)
        .collect();
    let mut map_width = 0.0;
    if bars.len() > 1 {
        let id = ui.scope_id().with(("shown series", title));
        let mut chosen = ui
            .data(|d| d.get_temp::<String>(id))
            .filter(|c| bars.iter().any(|s| &s.name == c))
            .unwrap_or_else(|| bars[0].name.clone());
        egui::ComboBox::from_id_salt(id)
            .selected_text(&chosen)
            .show_ui(ui, |ui| {
                for s in &bars {
                    ui.selectable_value(&mut chosen, s.name.clone(), &s.name);
                }
            });
        ui.data_mut(|d| d.insert_temp(id, chosen.clone()));
        series.retain(|s| s.kind != PlotKind::Bars || s.name == chosen);
        map_width = (ui.available_width() * 0.4).min(plot_height(ui) * 1.5);
    }
    let Some(first) = series.first() else { return };
    let height = plot_height(ui);
    // Beside the chosen bars, every series at once as a grid (MMLT: k by s).
    ui.horizontal_top(|ui| {
        if map_width > 0.0 {
            series_map(ui, &bars, egui::vec2(map_width, height));
        }
        cheap_plot(("integrator plot", title))
            .height(height)
            .width(ui.available_width())
            .legend(Legend::default())
            .x_axis_label(first.x_label.clone())
            .y_axis_label(first.y_label.clone())
            .show(ui, |plot| {
                for s in &series {
                    match s.kind {
                        PlotKind::Line => plot.line(Line::new(
                            s.name.clone(),
                            PlotPoints::from(s.points.clone()),
                        )),
                        PlotKind::Bars => {
                            let bars = s
                                .points
                                .iter()
                                .enumerate()
                                .map(|(i, p)| {
                                    let bar = Bar::new(p[0], p[1]);
                                    match s.point_names.get(i) {
                                        Some(name) => bar.name(name),
                                        None => bar,
                                    }
                                })
                                .collect();
                            plot.bar_chart(BarChart::new(s.name.clone(), bars));
                        }
                    }
                }
            });
    });
}

/// Bar series side by side as a grid, a row per series and a column per bar, each cell's
/// colour its share (dark: none, bright yellow: all): MMLT's whole technique histogram, a
/// row per path length k and a column per technique s. Hovering a cell names it.
fn series_map(ui: &mut egui::Ui, series: &[&PlotSeries], size: egui::Vec2) {
    let (rect, response) = ui.allocate_exact_size(size, egui::Sense::hover());
    let columns = series
        .iter()
        .map(|s| s.points.len())
        .max()
        .unwrap_or(1)
        .max(1);
    let rows = series.len().max(1);
    let label_width = 36.0;
    let cell = egui::vec2(
        (rect.width() - label_width) / columns as f32,
        rect.height() / rows as f32,
    );
    let painter = ui.painter_at(rect);
    let text = ui.visuals().text_color();
    let mut hovered = None;
    for (row, s) in series.iter().enumerate() {
        let y = rect.top() + row as f32 * cell.y;
        painter.text(
            egui::pos2(rect.left(), y + cell.y / 2.0),
            egui::Align2::LEFT_CENTER,
            &s.name,
            egui::FontId::proportional(cell.y.clamp(6.0, 11.0)),
            text,
        );
        for (column, p) in s.points.iter().enumerate() {
            let min = egui::pos2(rect.left() + label_width + column as f32 * cell.x, y);
            let cell_rect = egui::Rect::from_min_size(min, cell).shrink(0.5);
            painter.rect_filled(cell_rect, 0.0, share_colour(p[1]));
            if response.hover_pos().is_some_and(|h| cell_rect.contains(h)) {
                let name = s.point_names.get(column).cloned().unwrap_or_default();
                hovered = Some(format!("{}, {name}: {:.1} %", s.name, p[1] * 100.0));
            }
        }
    }
    if let Some(h) = hovered {
        response.on_hover_text(h);
    }
}

/// A dark-blue-to-yellow ramp for a share in [0, 1], brightening like its square root so
/// that small shares stay visible.
fn share_colour(share: f64) -> egui::Color32 {
    let t = share.clamp(0.0, 1.0).sqrt() as f32;
    let lerp = |a: f32, b: f32| (a + (b - a) * t) as u8;
    egui::Color32::from_rgb(lerp(20.0, 250.0), lerp(20.0, 230.0), lerp(70.0, 40.0))
}

fn convergence_plot(
    ui: &mut egui::Ui,
    log_points: &dyn Fn(fn(&caustica_renderer::image::ErrorMetrics) -> f64) -> PlotPoints<'static>,
    estimated: PlotPoints<'static>,
) {
    cheap_plot("convergence")
        .height(plot_height(ui))
        .legend(Legend::default())
        .x_axis_label("seconds")
        .y_axis_label("error")
        .x_axis_formatter(power_of_ten)
        .y_axis_formatter(power_of_ten)
        .show(ui, |plot| {
            plot.line(Line::new("relMSE", log_points(|m| m.rel_mse)));
            plot.line(Line::new("RMSE", log_points(|m| m.rmse)));
            plot.line(
                Line::new("estimated relMSE", estimated)
                    .style(egui_plot::LineStyle::dashed_loose()),
            );
        });
}

#[cfg(test)]
mod tests {
    use super::*;
    use egui_kittest::Harness;
    use egui_kittest::kittest::Queryable;

    #[test]
    fn integrator_plots_appear_beside_the_convergence_plot() {
        let convergence = Convergence::new(std::sync::Arc::new(|| {}));
        let series = vec![
            PlotSeries {
                plot: "Radius".into(),
                name: "mean".into(),
                kind: PlotKind::Line,
                x_label: "passes".into(),
                y_label: "radius".into(),
                points: vec![[1.0, 0.1], [2.0, 0.08]],
                point_names: Vec::new(),
            },
            PlotSeries {
                plot: "Techniques".into(),
                name: "k = 3".into(),
                kind: PlotKind::Bars,
                x_label: "s".into(),
                y_label: "share".into(),
                points: vec![[0.0, 0.5], [1.0, 0.5]],
                point_names: vec!["s = 0, t = 5".into(), "s = 1, t = 4".into()],
            },
        ];
        let harness = Harness::builder()
            .with_size(egui::vec2(900.0, 250.0))
            .build_ui(|ui| {
                plots_panel(ui, &convergence, &series);
            });
        harness.get_by_label("Radius");
        harness.get_by_label("Techniques");
        harness.get_by_label("Convergence");
    }
}
