//! Fast Phasor Fields for planar wall grids (docs/reconstruction.md): for each frequency and depth plane, the
//! camera-side RSD sum over the wall grid is a 2-D linear convolution, done by zero-padded FFTs and
//! cropped where no wrap-around can reach. The single point of the other side gets its exact per-voxel
//! phase afterwards; confocal captures use the round-trip kernel e^{2ikr}. Volumes whose lateral samples
//! are not on the wall lattice read the convolution through a windowed-sinc resampler.
//!
//! # Plan and executor
//!
//! What is computed and how are kept apart, so that another executor (a GPU's) can take the same
//! plan:
//! - [`FastPlan`] (`plan.rs`) is *what*: built once per capture geometry and volume, it holds the
//!   wall grid, the FFT sizes, the resamplers and Kaiser–Bessel kernels (with their inverse spectra)
//!   and the kernel's fold; per run it makes a `Schedule` (the depth planes of `depths.rs`, their
//!   slabs and time windows, chosen by the slab cost model for the executor's width) and says, per
//!   band frequency, how the field is read (`Reading`: kernels, kept lines, x band) and which
//!   histogram feeds each grid cell. It never starts threads or uses SIMD.
//! - [`Executor`] is *how*: its `Cpu` variant (`cpu/`)
//!   keeps a workspace per rayon worker and runs the grid spectra, the kernel's spectrum, the
//!   products, inverse transforms and resampling in wide loops. Another executor implements the
//!   three things the plan asks of it: `workers` (how many planes run at once, for the cost
//!   model), `each` (the planning's per-plane path ranges) and `run` (the field at every voxel for
//!   a schedule, planes in the volume's order), which must give the CPU's values to within f32
//!   rounding.

use crate::Progress;
use murk_core::{Capture, Result};
use rustfft::num_complex::Complex32;

mod cpu;
mod depths;
mod plan;
pub use plan::{FastPlan, Slab};

/// Where a [`FastPlan`] runs (see the module docs).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Executor {
    /// rayon's worker threads, with AVX products where the CPU has them.
    Cpu,
}

impl Executor {
    /// How many planes run at once: the width the slab cost model shares planes over.
    fn workers(self) -> usize {
        match self {
            Executor::Cpu => cpu::workers(),
        }
    }

    /// `f` at each depth of `zs` (independent evaluations while planning).
    fn each<T: Send>(self, zs: &[f64], f: impl Fn(f64) -> T + Sync) -> Vec<T> {
        match self {
            Executor::Cpu => cpu::each(zs, f),
        }
    }

    /// The field at every voxel of `plan`'s volume from `data`, evaluated as `schedule` says.
    fn run(
        self,
        plan: &FastPlan,
        schedule: &plan::Schedule,
        data: &Capture,
        progress: &dyn Progress,
    ) -> Vec<Complex32> {
        match self {
            Executor::Cpu => cpu::run(plan, schedule, data, progress),
        }
    }
}

impl FastPlan {
    /// The field at every voxel from `data` (a capture of this plan's geometry), and the depth slabs
    /// it was computed in, on the CPU.
    pub fn run(
        &self,
        data: &Capture,
        sigma_m: f64,
        wavelength_m: f64,
        progress: &dyn Progress,
    ) -> Result<(Vec<Complex32>, Vec<Slab>)> {
        let exec = Executor::Cpu;
        let schedule = self.schedule(sigma_m, wavelength_m, exec)?;
        let field = exec.run(self, &schedule, data, progress);
        Ok((field, schedule.reported()))
    }
}
