//! The file dialogs: a scene to open, a reference to compare with, an environment image.

use crate::viewer::ViewerApp;
use crate::viewer::command::Command;
use eframe::egui;
use std::path::{Path, PathBuf};

/// What an open file dialog is choosing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum DialogPurpose {
    Scene,
    Reference,
    Environment,
}

impl ViewerApp {
    pub(super) fn show_dialog(&mut self, purpose: DialogPurpose) {
        let start = self
            .settings
            .recent_scenes
            .first()
            .and_then(|p| p.parent())
            .map(Path::to_path_buf);
        let filter: egui_file::Filter<PathBuf> = match purpose {
            DialogPurpose::Scene => {
                Box::new(|p: &Path| p.extension().is_some_and(|e| e == "gltf" || e == "glb"))
            }
            DialogPurpose::Reference => {
                Box::new(|p: &Path| p.extension().is_some_and(|e| e == "exr"))
            }
            DialogPurpose::Environment => Box::new(|p: &Path| {
                p.extension()
                    .is_some_and(|e| e.eq_ignore_ascii_case("exr") || e.eq_ignore_ascii_case("hdr"))
            }),
        };
        let mut dialog = egui_file::FileDialog::open_file().show_files_filter(filter);
        if let Some(start) = start {
            dialog = dialog.initial_path(start);
        }
        dialog.open();
        self.open_dialog = Some((purpose, dialog));
    }

    pub(super) fn file_dialog(&mut self, ctx: &egui::Context) {
        let Some((purpose, dialog)) = &mut self.open_dialog else {
            return;
        };
        let purpose = *purpose;
        if dialog.show(ctx).selected() {
            if let Some(path) = dialog.path().map(Path::to_path_buf) {
                self.apply(match purpose {
                    DialogPurpose::Scene => Command::OpenScene(path),
                    DialogPurpose::Reference => Command::LoadReference(path),
                    DialogPurpose::Environment => {
                        Command::SetEnvironment(path.display().to_string())
                    }
                });
            }
            self.open_dialog = None;
        } else if !dialog.visible() {
            self.open_dialog = None;
        }
    }
}
