//! Snapshots: the current estimate saved as EXR (linear, with the run's metadata) or PNG
//! (as displayed), written on a helper thread whose result comes back as a message, so a
//! slow or failed save never stops the render or the UI.

use crate::viewer::ViewerApp;
use caustica_renderer::image::{write_exr, write_png_tone_mapped};
use caustica_renderer::metadata::exr_metadata;
use std::path::PathBuf;

impl ViewerApp {
    /// Default snapshot name: scene, integrator and UTC time.
    pub fn snapshot_path(&self, extension: &str) -> PathBuf {
        let scene = self
            .controller
            .scene()
            .and_then(|s| s.path.file_stem())
            .map_or("render".to_string(), |s| s.to_string_lossy().into_owned());
        let time = humantime::format_rfc3339_seconds(std::time::SystemTime::now())
            .to_string()
            .replace(':', "-");
        self.snapshot_dir.join(format!(
            "{scene}-{}-{time}.{extension}",
            self.settings.integrator
        ))
    }

    /// Writes the current estimate on a helper thread; the result comes back as a message.
    pub(super) fn save_snapshot(&mut self, png: bool) {
        let Some(frame) = self.controller.frame() else {
            self.error("nothing to save: no render is running");
            return;
        };
        let path = self.snapshot_path(if png { "png" } else { "exr" });
        let (exposure, curve) = (self.settings.exposure, self.settings.tone_curve);
        let scene = self
            .controller
            .scene()
            .map(|s| s.path.clone())
            .unwrap_or_default();
        let Some(session) = self.controller.session() else {
            self.error("nothing to save: no render is running");
            return;
        };
        let metadata = exr_metadata(&session.run_description(&scene), &frame);
        let tx = self.saves.0.clone();
        std::thread::spawn(move || {
            let result = if png {
                write_png_tone_mapped(&path, &frame.image, exposure, curve)
            } else {
                write_exr(&path, &frame.image, &metadata)
            };
            let _ = tx.send(
                result
                    .map(|()| path)
                    .map_err(|e| format!("cannot save: {e}")),
            );
        });
    }

    /// Reports the saves that finished since the last frame.
    pub(super) fn poll_saves(&mut self) {
        while let Ok(result) = self.saves.1.try_recv() {
            match result {
                Ok(path) => self.info(format!("saved {}", path.display())),
                Err(e) => self.error(e),
            }
        }
    }
}
