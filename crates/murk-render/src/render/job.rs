//! The mapping from work units (tiles of traced wall points) to wall points, targets and histograms,
//! and the rendering of one unit.

use crate::integrator::{Endpoint, Sampler, Tracer};
use crate::scene::{Scene, TraceFrom};
use murk_core::{Capture, DVec3, Error, Pairing, PointLayout, Result};
use std::sync::Arc;

/// The mapping from work units to wall points and histograms.
pub struct Plan<'a> {
    pub scene: &'a Scene,
    tracer: Tracer<'a>,
    from_laser: bool,
    /// The traced points' grid (nx, ny; a list is n × 1) and the tile (tx, ty) of one unit; tiles divide
    /// the grid.
    grid: (usize, usize),
    tile: (usize, usize),
    /// The medium albedos rendered from the same paths, one capture each (empty: the scene's own).
    pub(super) albedos: Vec<f64>,
    /// Each capture's albedo over the scene medium's own (one 1 for a plain render).
    pub(super) ratios: Vec<f64>,
}

/// Most albedos one sweep renders.
pub const MAX_SWEEP: usize = 16;

impl<'a> Plan<'a> {
    pub fn new(scene: &'a Scene) -> Self {
        let c = &scene.capture;
        let from_laser = match scene.settings.trace_from {
            TraceFrom::Laser => true,
            TraceFrom::Sensor => false,
            // Trace from the larger side: each vertex then connects to the few points of the other side.
            TraceFrom::Auto => c.illum.len() >= c.sensor.len(),
        };
        let traced = if from_laser { &c.illum } else { &c.sensor };
        let grid = match traced.layout {
            PointLayout::Grid { nx, ny } => (nx, ny),
            PointLayout::List => (traced.len(), 1),
        };
        // Tails are shared where a medium scatters (their density model) and every traced point has the
        // same targets; the tile side is the largest divisor of each grid side up to `share_tile`.
        let side = if scene.scatters()
            && c.pairing == Pairing::Product
            && traced.layout != PointLayout::List
        {
            scene.settings.share_tile.max(1) as usize
        } else {
            1
        };
        let fit = |n: usize| {
            (1..=side.min(n))
                .rev()
                .find(|t| n.is_multiple_of(*t))
                .unwrap_or(1)
        };
        Plan {
            scene,
            tracer: Tracer::new(scene),
            from_laser,
            grid,
            tile: (fit(grid.0), fit(grid.1)),
            albedos: Vec::new(),
            ratios: vec![1.0],
        }
    }

    /// A plain render of `scene` without `albedos`, else a [`Plan::sweep`] over them.
    pub fn with_albedos(scene: &'a Scene, albedos: Option<&[f64]>) -> Result<Self> {
        match albedos {
            None => Ok(Self::new(scene)),
            Some(a) => Self::sweep(scene, a),
        }
    }

    /// A plan that renders one capture per medium albedo in `albedos` from the same paths. In a
    /// scattering medium no path's sampling depends on the albedo (there is no roulette there unless
    /// `render.rr_depth` asks for it), so each contribution only scales by the albedo to the power of its
    /// medium scattering events: capture j equals, up to float rounding, the capture of the scene with
    /// `medium.albedo = albedos[j]` and the same seed. The tracing is paid once; only the histogram
    /// writes are paid per albedo.
    pub fn sweep(scene: &'a Scene, albedos: &[f64]) -> Result<Self> {
        let own = scene
            .medium
            .as_ref()
            .filter(|_| scene.scatters())
            .map(|m| m.albedo);
        let Some(own) = own else {
            return Err(Error::param(
                "an albedo sweep needs a scattering medium (medium.mu_t > 0 and medium.albedo > 0)",
            ));
        };
        if albedos.is_empty() || albedos.len() > MAX_SWEEP {
            return Err(Error::param(format!(
                "an albedo sweep takes 1 to {MAX_SWEEP} albedos, got {}",
                albedos.len()
            )));
        }
        // At α = 0 a plain render takes the estimator of a medium that only absorbs, and a roulette's
        // survival depends on the path's throughput: a sweep would not equal either render.
        if let Some(a) = albedos.iter().find(|a| !(**a > 0.0 && **a <= 1.0)) {
            return Err(Error::param(format!(
                "albedo {a} of the sweep: must be in (0, 1] (render albedo 0 alone)"
            )));
        }
        if scene.settings.rr_depth.is_some() {
            return Err(Error::param(
                "an albedo sweep needs render.rr_depth unset: Russian roulette depends on the albedo",
            ));
        }
        let twice = (1..albedos.len()).find(|&i| albedos[..i].contains(&albedos[i]));
        if let Some(i) = twice {
            return Err(Error::param(format!(
                "albedo {} appears twice in the sweep",
                albedos[i]
            )));
        }
        let mut plan = Plan::new(scene);
        murk_core::Limits::get().elements(
            "the sweep's captures",
            &[albedos.len(), plan.n_hists(), scene.capture.time.bins],
            4,
        )?;
        plan.albedos = albedos.to_vec();
        plan.ratios = albedos.iter().map(|a| a / own).collect();
        Ok(plan)
    }

    /// Work units: tiles.
    pub fn n_units(&self) -> usize {
        (self.grid.0 / self.tile.0) * (self.grid.1 / self.tile.1)
    }

    /// Traced wall points (laser points when tracing from lasers).
    pub fn n_points(&self) -> usize {
        self.grid.0 * self.grid.1
    }

    /// The traced points of unit `u`, a tile (x-major like the grid, so tile rows are grid rows).
    fn unit_points(&self, u: usize) -> impl Iterator<Item = usize> + '_ {
        let (tx, ty) = self.tile;
        let tiles_y = self.grid.1 / ty;
        let (a, b) = (u / tiles_y, u % tiles_y);
        (0..tx).flat_map(move |i| (0..ty).map(move |j| (a * tx + i) * self.grid.1 + b * ty + j))
    }

    /// Traced points in shard `(i, n)`.
    pub fn shard_points(&self, shard: Option<(usize, usize)>) -> usize {
        self.shard_units(shard).len() * self.tile.0 * self.tile.1
    }

    fn endpoint(&self, laser: bool, i: usize) -> Endpoint {
        let c = &self.scene.capture;
        let (set, dev) = if laser {
            (&c.illum, c.laser_xyz)
        } else {
            (&c.sensor, c.sensor_xyz)
        };
        let p = set.points[i];
        let extra_m = match (c.account_first_and_last_bounces, dev) {
            (true, Some(x)) => (p - x).length(),
            _ => 0.0,
        };
        Endpoint {
            p,
            n: DVec3::Z,
            extra_m,
        }
    }

    /// How many targets each traced point has: the other side's points, or its partner (paired).
    fn n_targets(&self) -> usize {
        let c = &self.scene.capture;
        match c.pairing {
            Pairing::Paired => 1,
            Pairing::Product if self.from_laser => c.sensor.len(),
            Pairing::Product => c.illum.len(),
        }
    }

    /// The targets of traced point `p`.
    fn targets(&self, p: usize) -> Vec<Endpoint> {
        match self.scene.capture.pairing {
            Pairing::Paired => vec![self.endpoint(!self.from_laser, p)],
            Pairing::Product => (0..self.n_targets())
                .map(|k| self.endpoint(!self.from_laser, k))
                .collect(),
        }
    }

    /// The histogram of traced point `p` with its target `k`.
    fn hist(&self, p: usize, k: usize) -> usize {
        let n_sensor = self.scene.capture.sensor.len();
        match self.scene.capture.pairing {
            Pairing::Paired => p,
            Pairing::Product if self.from_laser => p * n_sensor + k,
            Pairing::Product => k * n_sensor + p,
        }
    }

    /// Renders unit `u`: per traced point of the tile, one normalised histogram per target, in order.
    pub fn render_unit(&self, u: usize, spp: u64, seed: u64) -> Vec<f32> {
        let points: Vec<usize> = self.unit_points(u).collect();
        let origins: Vec<Endpoint> = points
            .iter()
            .map(|&p| self.endpoint(self.from_laser, p))
            .collect();
        // A tile of more than one point has product pairing: its points share their targets.
        let targets = self.targets(points[0]);
        // f32 sums: a tile's accumulator takes half the memory of f64's, and the shared
        // tails' scattered adds miss the cache less (docs/renderer-sampling.md); their rounding stays
        // near 1e-6 of each bin at thousands of spp, far below the Monte Carlo error.
        let mut acc = vec![0.0f32; self.unit_len()];
        let mut s = Sampler::new(seed, u as u64);
        let sweep = (spp, &self.ratios[..]);
        self.tracer
            .trace(&origins, &targets, sweep, &mut s, &mut acc);
        let norm = 1.0 / spp as f64;
        acc.iter().map(|&v| (v as f64 * norm) as f32).collect()
    }

    /// Copies unit `u`'s histograms into the captures (a sweep's bins hold one value per capture).
    pub(super) fn store(&self, caps: &mut [Capture], u: usize, buf: &[f32]) {
        let nt = self.scene.capture.time.bins;
        let n = caps.len();
        let hists = self
            .unit_points(u)
            .flat_map(|p| (0..self.n_targets()).map(move |k| self.hist(p, k)));
        for (k, hist) in hists.enumerate() {
            let src = &buf[k * nt * n..(k + 1) * nt * n];
            if n == 1 {
                caps[0].h[hist * nt..(hist + 1) * nt].copy_from_slice(src);
                continue;
            }
            for (j, cap) in caps.iter_mut().enumerate() {
                let dst = &mut cap.h[hist * nt..(hist + 1) * nt];
                dst.iter_mut()
                    .zip(src.iter().skip(j).step_by(n))
                    .for_each(|(d, s)| *d = *s);
            }
        }
    }

    /// The units shard `(i, n)` renders. Units are taken in a golden-ratio order (unit j·g mod N
    /// for g ≈ 0.618·N coprime with N) and dealt to the shards in turn, so that each shard gets a like
    /// share of every part of the wall (costly and cheap tiles alike) and shards on equal workers end
    /// together.
    pub fn shard_units(&self, shard: Option<(usize, usize)>) -> Vec<usize> {
        let n = self.n_units();
        let Some((i, k)) = shard else {
            return (0..n).collect();
        };
        let gcd = |mut a: usize, mut b: usize| {
            while b != 0 {
                (a, b) = (b, a % b);
            }
            a
        };
        let mut g = ((n as f64 * 0.618_033_988_75).round() as usize).max(1);
        while gcd(g, n) != 1 {
            g += 1;
        }
        (i..n).step_by(k.max(1)).map(|j| j * g % n).collect()
    }

    fn n_hists(&self) -> usize {
        let c = &self.scene.capture;
        match c.pairing {
            Pairing::Paired => c.illum.len(),
            Pairing::Product => c.illum.len() * c.sensor.len(),
        }
    }

    /// An all-zero capture with this scene's layout.
    pub fn empty_capture(&self, scene_info: String) -> Capture {
        let c = &self.scene.capture;
        let n_hist = self.n_hists();
        Capture {
            laser_xyz: c.laser_xyz,
            sensor_xyz: c.sensor_xyz,
            t_accounts_first_and_last_bounces: c.account_first_and_last_bounces,
            scene_info,
            medium_density: self.scene.medium.as_ref().and_then(|m| match &m.kind {
                crate::medium::Kind::Grid(g) => Some(Arc::new(g.cells().clone())),
                _ => None,
            }),
            ..Capture::new(
                c.illum.clone(),
                c.sensor.clone(),
                c.pairing,
                c.time,
                vec![0.0; n_hist * c.time.bins],
            )
        }
    }

    /// A sweep's several captures are refused before any work rather than dropped after it.
    pub(super) fn plain_only(&self) -> Result<()> {
        match self.albedos.len() {
            0 => Ok(()),
            n => Err(Error::param(format!(
                "an albedo sweep renders {n} captures: render_all_until or assemble_all returns them"
            ))),
        }
    }

    /// What a capture gets once all its units are in: the devices' radiometry, if the scene asks.
    pub(super) fn finish(&self, cap: &mut Capture) {
        let spec = &self.scene.capture;
        if let (true, Some(laser), Some(spad)) =
            (spec.device_radiometry, spec.laser_xyz, spec.sensor_xyz)
        {
            cap.apply_device_radiometry(laser, spad);
        }
    }

    pub(super) fn unit_len(&self) -> usize {
        self.ratios.len()
            * self.n_targets()
            * self.scene.capture.time.bins
            * self.tile.0
            * self.tile.1
    }
}
