//! The desktop viewer (eframe on wgpu): opens a glTF scene, renders it progressively in the
//! background, shows the image as it converges, and saves snapshots.

pub mod app;
pub mod automation;
pub mod command;
pub mod controller;
pub mod convergence;
pub mod dialogs;
pub mod error_map;
pub mod navigation;
pub mod panels;
pub mod plots;
pub mod repaint;
pub mod settings;
pub mod snapshot;
pub mod state;
pub mod tonemap;
pub mod viewport;

pub use automation::Automation;
pub use command::{Command, Message};
pub use state::{ViewerApp, ViewerOptions};

/// Opens the viewer window and runs until it is closed.
pub fn run(options: ViewerOptions) -> eframe::Result<()> {
    let native = eframe::NativeOptions {
        viewport: eframe::egui::ViewportBuilder::default()
            .with_title("Caustica")
            .with_inner_size(options.window_size.unwrap_or([1280.0, 800.0]))
            .with_drag_and_drop(true),
        renderer: eframe::Renderer::Wgpu,
        // A size asked for on the command line wins over the remembered one.
        persist_window: options.window_size.is_none(),
        ..Default::default()
    };
    eframe::run_native(
        "Caustica",
        native,
        Box::new(|cc| Ok(Box::new(ViewerApp::new(cc, options)))),
    )
}
