//! # epsm-viewer: an interactive front end over epsm-core
//!
//! A thin eframe/egui application (see `docs/viewer.md`): it opens a
//! problem file, runs the optimization on a worker thread ([`worker`]),
//! and shows the current render, the target, their signed difference, the
//! parameters (with sliders that move the scene), a live plot of image
//! RMSE and parameter error, and the gradient overlay of one parameter
//! (`dp/dθ` arrows and flow colours, `dI/dθ` heat map, OT matching lines).
//! Every number it shows comes from epsm-core ([`epsm_core::inspect`],
//! [`epsm_core::field`], [`epsm_core::Optimization`]); the viewer does no
//! math of its own.
//!
//! [`app::ViewerApp::show`] draws one frame into any `egui::Ui`, so the UI
//! runs headless under `egui_kittest` in the tests.

pub mod app;
pub mod overlay;
pub mod panels;
pub mod plot;
pub mod recent;
pub mod screenshot;
pub mod state;
pub mod textures;
pub mod worker;

pub use app::{Options, ViewerApp};
