//! The measuring lab: what tells how accurate and how fast the effects are, on its own floor
//! (no module of the product imports it; only the command line runs its commands).
//!
//! - [`truth`]: procedural scenes with closed-form motion and their brute-force references
//!   (`shutter scene`);
//! - [`metrics`]: RMSE, PSNR, SSIM, FLIP;
//! - [`diff`]: comparing two sequences (`shutter diff`);
//! - [`bench`]: the time-against-error sweep over the truth scenes (`shutter bench`).

pub mod bench;
pub mod diff;
pub mod metrics;
pub mod truth;
