//! `fovea view`: a window that renders continuously, its fovea following the gaze (the mouse pointer,
//! an eye tracker over UDP, or a replayed trace), with fly controls, keys, on-screen figures,
//! per-pixel history that survives gaze and camera moves, and a frame-time budget (README, "Live
//! view"; docs/view.md).
//!
//! Modules, one concept each: [`options`] (the command line, checked), [`sampling`] (configurations and
//! the budget), [`gaze`] (UDP and trace sources), [`script`] (scripted input), [`fly`] (camera controls),
//! [`hud`] (on-screen text), [`live`] (rendering and presenting), [`record`] (per-frame figures and
//! screenshots) and [`app`] (the window and its event loop, which ties them together).
#[cfg(feature = "vulkan")]
mod app;
pub mod fly;
pub mod hud;
#[cfg(feature = "vulkan")]
mod live;
mod options;
#[cfg(feature = "vulkan")]
mod record;
pub mod sampling;
pub mod script;

use crate::args::ViewArgs;
use crate::error::Result;

/// Runs `fovea view`.
#[cfg(feature = "vulkan")]
pub fn run(args: &ViewArgs) -> Result<()> {
    let options = options::ViewOptions::from_args(args)?;
    app::run(options)
}

/// Runs `fovea view` (this build cannot: the window is presented through Vulkan).
#[cfg(not(feature = "vulkan"))]
pub fn run(args: &ViewArgs) -> Result<()> {
    let _ = options::ViewOptions::from_args(args)?;
    Err(crate::error::FoveaError::View(
        "this build of fovea has no Vulkan backend (built without the `vulkan` feature), which the \
         view presents through"
            .into(),
    ))
}
