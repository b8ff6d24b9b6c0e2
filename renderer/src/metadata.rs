//! What Caustica writes beside every image it saves: the EXR header attributes (DESIGN.md
//! section 3), built in this one place for the command line and the viewer from the
//! session's own account of its run (`Session::run_description`).

use crate::camera::{CameraDesc, Projection};
use crate::integrators::params_json;
use crate::session::{Frame, RunDescription};
use std::collections::BTreeMap;

/// Header attributes (written as `caustica:KEY`) of `frame`, rendered by `run`.
///
/// `automatic` gives the values chosen for parameters left automatic (JSON, absent when none);
/// `passes` and `samples_per_pixel` count passes (one sample per pixel each for pt and bdpt,
/// one eye pass and a photon pass for the photon mappers, width x height mutations for mmlt);
/// `samples` counts every sample the integrator took; `estimated_relmse` is the remaining
/// error estimated without a reference, and `estimated_bias_relmse` its squared-bias part.
pub fn exr_metadata(run: &RunDescription, frame: &Frame) -> BTreeMap<String, String> {
    let mut m = BTreeMap::from([
        ("integrator".to_string(), run.integrator.clone()),
        ("parameters".to_string(), params_json(&run.params)),
        (
            "elapsed_seconds".to_string(),
            format!("{:.3}", frame.elapsed.as_secs_f64()),
        ),
        ("passes".to_string(), frame.passes.to_string()),
        ("samples_per_pixel".to_string(), frame.passes.to_string()),
        ("samples".to_string(), frame.samples.to_string()),
        ("seed".to_string(), run.seed.to_string()),
        ("scene".to_string(), run.scene.display().to_string()),
        ("environment".to_string(), run.environment.clone()),
        ("camera".to_string(), camera_to_json(&run.camera)),
        ("threads".to_string(), run.threads.to_string()),
        ("rays".to_string(), frame.rays.to_string()),
        ("dropped_samples".to_string(), frame.dropped.to_string()),
    ]);
    // What the integrator chose for parameters given as 0 (`caustica:parameters` keeps the
    // 0 that was asked for), so that the run can be repeated with the same values.
    if !frame.automatic.is_empty() {
        let chosen: serde_json::Map<String, serde_json::Value> = frame
            .automatic
            .iter()
            .map(|(name, value)| (name.to_string(), serde_json::json!(value)))
            .collect();
        m.insert(
            "automatic".into(),
            serde_json::Value::Object(chosen).to_string(),
        );
    }
    if let Some(e) = frame.error.as_ref() {
        m.insert("estimated_relmse".into(), format!("{:e}", e.rel_mse));
        m.insert(
            "estimated_bias_relmse".into(),
            format!("{:e}", e.bias_rel_mse),
        );
    }
    m
}

/// The `camera` attribute: the view as JSON, its position, its rotation as a unit quaternion
/// (x, y, z, w; the camera looks down its -Z with +Y up, as in glTF), its projection with the
/// vertical field of view in degrees or the film's half height, and the film's aspect, so that
/// `camera_from_json` (`caustica render --camera-from`) renders the same view.
pub fn camera_to_json(camera: &CameraDesc) -> String {
    let (_, rotation, position) = camera.camera_to_world.to_scale_rotation_translation();
    let projection = match camera.projection {
        Projection::Perspective { yfov } => {
            serde_json::json!({"type": "perspective", "yfov_degrees": yfov.to_degrees()})
        }
        Projection::Orthographic { ymag } => {
            serde_json::json!({"type": "orthographic", "ymag": ymag})
        }
    };
    serde_json::json!({
        "position": position.to_array(),
        "rotation": rotation.to_array(),
        "projection": projection,
        "aspect": camera.aspect,
    })
    .to_string()
}

/// Reads what `camera_to_json` wrote; the error says what is missing or wrong.
pub fn camera_from_json(text: &str) -> Result<CameraDesc, String> {
    use glam::{Affine3A, Quat, Vec3};
    let v: serde_json::Value =
        serde_json::from_str(text).map_err(|e| format!("the camera is not JSON: {e}"))?;
    let numbers = |key: &str, n: usize| -> Result<Vec<f32>, String> {
        let array = v[key]
            .as_array()
            .filter(|a| a.len() == n)
            .ok_or_else(|| format!("the camera's {key} is not {n} numbers"))?;
        array
            .iter()
            .map(|x| {
                x.as_f64()
                    .map(|x| x as f32)
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| {
                        format!("the camera's {key} holds a value that is not a finite number")
                    })
            })
            .collect()
    };
    let position = Vec3::from_slice(&numbers("position", 3)?);
    let rotation = Quat::from_slice(&numbers("rotation", 4)?);
    if (rotation.length() - 1.0).abs() > 1e-3 {
        return Err("the camera's rotation is not a unit quaternion".into());
    }
    let p = &v["projection"];
    let positive = |key: &str| {
        p[key]
            .as_f64()
            .map(|x| x as f32)
            .filter(|x| x.is_finite() && *x > 0.0)
            .ok_or_else(|| format!("the camera's projection has no positive {key}"))
    };
    let projection = match p["type"].as_str() {
        Some("perspective") => {
            let yfov = positive("yfov_degrees")?;
            if yfov >= 180.0 {
                return Err("the camera's field of view is not under 180 degrees".into());
            }
            Projection::Perspective {
                yfov: yfov.to_radians(),
            }
        }
        Some("orthographic") => Projection::Orthographic {
            ymag: positive("ymag")?,
        },
        _ => return Err("the camera's projection is neither perspective nor orthographic".into()),
    };
    let aspect = v["aspect"]
        .as_f64()
        .map(|a| a as f32)
        .filter(|a| a.is_finite() && *a > 0.0);
    Ok(CameraDesc {
        camera_to_world: Affine3A::from_rotation_translation(rotation.normalize(), position),
        projection,
        aspect,
    })
}

#[cfg(test)]
mod camera_tests {
    use super::*;
    use glam::{Affine3A, Quat, Vec3};

    #[test]
    fn a_camera_survives_the_header_and_bad_ones_are_refused() {
        for projection in [
            Projection::Perspective { yfov: 0.7 },
            Projection::Orthographic { ymag: 2.5 },
        ] {
            let camera = CameraDesc {
                camera_to_world: Affine3A::from_rotation_translation(
                    Quat::from_euler(glam::EulerRot::YXZ, 0.4, -0.3, 0.0),
                    Vec3::new(1.0, 2.0, -3.0),
                ),
                projection,
                aspect: Some(1.5),
            };
            let back = camera_from_json(&camera_to_json(&camera)).unwrap();
            assert!(
                back.camera_to_world
                    .abs_diff_eq(camera.camera_to_world, 1e-5)
            );
            assert_eq!(back.aspect, camera.aspect);
            match (back.projection, projection) {
                (Projection::Perspective { yfov: a }, Projection::Perspective { yfov: b }) => {
                    assert!((a - b).abs() < 1e-6)
                }
                (a, b) => assert_eq!(a, b),
            }
        }
        for (bad, says) in [
            ("not json", "not JSON"),
            (
                r#"{"position": [0, 0], "rotation": [0, 0, 0, 1]}"#,
                "position",
            ),
            (
                r#"{"position": [0, 0, 0], "rotation": [0, 0, 0, 2]}"#,
                "unit quaternion",
            ),
            (
                r#"{"position": [0, 0, 0], "rotation": [0, 0, 0, 1], "projection": {"type": "perspective", "yfov_degrees": 200}}"#,
                "180",
            ),
            (
                r#"{"position": [0, 0, 0], "rotation": [0, 0, 0, 1], "projection": {"type": "fisheye"}}"#,
                "neither",
            ),
        ] {
            let error = camera_from_json(bad).unwrap_err();
            assert!(error.contains(says), "{bad}: {error}");
        }
    }
}
