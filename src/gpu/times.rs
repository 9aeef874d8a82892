//! Where a GPU stage's time went ([`GpuTimes`]), for `shutter bench`'s GPU rows; in both
//! builds, so callers need no `cfg`.

use serde::Serialize;

/// Where a GPU stage's time went, ms, summed over the stages that ran: writing its inputs
/// into device memory, its dispatches, and copying its outputs back. Measured on the host,
/// with the queue drained between the three (see `Gpu::set_profiling`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct GpuTimes {
    pub upload_ms: f64,
    pub compute_ms: f64,
    pub readback_ms: f64,
}

impl GpuTimes {
    /// These sums over `runs` runs, per run.
    pub fn per_run(self, runs: usize) -> GpuTimes {
        let n = runs.max(1) as f64;
        GpuTimes {
            upload_ms: self.upload_ms / n,
            compute_ms: self.compute_ms / n,
            readback_ms: self.readback_ms / n,
        }
    }
}
