//! # caustica-renderer
//!
//! The CPU light-transport library behind Caustica. It knows nothing of any GUI.
//!
//! How the pieces fit (after pbrt-v4):
//! - [`scene::Scene`] is immutable once built (from glTF by [`scene::gltf::load`], or from a
//!   [`scene::SceneDescription`] in code) and shared by all threads through an `Arc`. It owns
//!   the triangles, [`material::Material`]s, [`light::Light`]s, the camera description and the
//!   BVH ([`scene::accel`]).
//! - A [`camera::Camera`] turns film positions into rays.
//! - Every random number comes from a [`sampling::sampler::Sampler`] keyed by (seed, pixel,
//!   sample index, dimension), so images do not depend on thread scheduling.
//! - An [`integrators::Integrator`] runs one progressive pass at a time, taking work from the
//!   sampler and writing to its [`film::Film`]; the registry in [`integrators`] lists every
//!   integrator with the description of its parameters.
//! - A [`session::Session`] runs passes on background threads and publishes the newest
//!   [`session::Frame`] without ever blocking the workers; the command line and the viewer
//!   both drive this one API.
//! - [`image`] holds linear images, EXR/PNG output and the error metrics of DESIGN.md section 3;
//!   [`error_estimate`] estimates that error without a reference, from the integrator's own
//!   samples, for every integrator and every frame.

pub mod advisor;
pub mod camera;
pub mod color;
pub mod error_estimate;
pub mod exposure;
pub mod film;
pub mod fuzzing;
pub mod geometry;
pub mod image;
pub mod integrators;
pub mod light;
pub mod material;
pub mod metadata;
pub mod preview;
pub mod procedural;
pub mod process;
pub mod sampling;
pub mod scene;
pub mod session;
pub mod survey;
pub mod texture;
pub mod texture_footprint;
