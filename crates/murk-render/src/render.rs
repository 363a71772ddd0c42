//! Work units, parallel rendering, checkpoints, shards, merging and assembling checkpoint parts.
//!
//! A work unit is a tile of traced wall points (laser points when tracing from lasers; one point unless
//! they share path tails, `share_tile`) with its own PCG stream (seed, unit index), rendered by one
//! thread into histograms nobody else writes. So the result does not depend on the thread count, on how
//! units are sharded, or on an interruption and `--resume`.

use crate::integrator::{Endpoint, Sampler, Tracer};
use crate::scene::{Scene, TraceFrom};
use murk_core::{Capture, DVec3, Error, Pairing, PointLayout, Result};
use rayon::prelude::*;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// How a render runs.
#[derive(Clone, Debug)]
pub struct RenderOptions {
    pub spp: u64,
    pub seed: u64,
    /// `(i, n)`: render only shard i of n (see [`Plan::shard_units`]).
    pub shard: Option<(usize, usize)>,
    /// Append finished units to this file every `checkpoint_every`; resume from it when it exists and matches.
    pub checkpoint: Option<PathBuf>,
    pub checkpoint_every: Duration,
}

const MAX_SECONDS: f64 = murk_core::Limits::MAX_SECONDS;
const MAX_SPP: u64 = murk_core::Limits::MAX_SPP;

/// The interval between checkpoint appends, from seconds (0: after every unit). Refuses negative,
/// non-finite and longer-than-a-year values.
pub fn checkpoint_interval(seconds: f64) -> Result<Duration> {
    match seconds {
        s if (0.0..=MAX_SECONDS).contains(&s) => Ok(Duration::from_secs_f64(s)),
        s => Err(Error::param(format!(
            "a checkpoint interval needs 0 ≤ seconds ≤ {MAX_SECONDS} (one year), got {}",
            murk_core::short(s)
        ))),
    }
}

/// A time budget for [`Plan::spp_for_budget`]: 0 < seconds ≤ one year.
pub fn time_budget(seconds: f64) -> Result<f64> {
    if seconds > 0.0 && seconds <= MAX_SECONDS {
        Ok(seconds)
    } else {
        Err(Error::param(format!(
            "a time budget needs 0 < seconds ≤ {MAX_SECONDS} (one year), got {}",
            murk_core::short(seconds)
        )))
    }
}

/// The checkpoint a render to `out` keeps: `out` with `.ckpt` appended.
pub fn checkpoint_path(out: &Path) -> PathBuf {
    let mut p = out.as_os_str().to_owned();
    p.push(".ckpt");
    PathBuf::from(p)
}

/// The checkpoint file and interval of a render to `out`, as `murk render` keeps them: without
/// `resume` an old `out.ckpt` is removed first, so the render starts afresh; `every_s` = 0 keeps no
/// checkpoint, except that `resume` still reads an existing one (then appending to it only if the
/// render is stopped or cannot store its captures).
pub fn output_checkpoint(
    out: &Path,
    resume: bool,
    every_s: f64,
) -> Result<Option<(PathBuf, Duration)>> {
    let every = checkpoint_interval(every_s)?;
    let path = checkpoint_path(out);
    if !resume && path.exists() {
        std::fs::remove_file(&path).map_err(|e| Error::io(&path, e))?;
    }
    Ok(match (every_s > 0.0, resume && path.exists()) {
        (true, _) => Some((path, every)),
        (false, true) => Some((path, Duration::MAX)),
        (false, false) => None,
    })
}

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
    albedos: Vec<f64>,
    /// Each capture's albedo over the scene medium's own (one 1 for a plain render).
    ratios: Vec<f64>,
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
        // f32 sums: a tile of 8 × 8 points with 4 096 bins then holds 1 MB instead of 2, and the shared
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
    fn store(&self, caps: &mut [Capture], u: usize, buf: &[f32]) {
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
            illum: c.illum.clone(),
            sensor: c.sensor.clone(),
            laser_xyz: c.laser_xyz,
            sensor_xyz: c.sensor_xyz,
            time: c.time,
            t_accounts_first_and_last_bounces: c.account_first_and_last_bounces,
            pairing: c.pairing,
            h: vec![0.0; n_hist * c.time.bins],
            scene_info,
        }
    }

    /// Renders (this shard of) the capture of a plain plan. `progress(done, total)` is called after
    /// each batch of units.
    pub fn render(
        &self,
        opt: &RenderOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
    ) -> Result<Capture> {
        self.plain_only()?;
        Ok(self
            .render_all_until(opt, progress, &AtomicBool::new(false))?
            .remove(0))
    }

    /// One capture per albedo of a sweep (one for a plain plan). No unit starts once `stop` is set
    /// (Ctrl-C): the call then returns an error, and the checkpoint keeps every unit finished before it.
    pub fn render_all_until(
        &self,
        opt: &RenderOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
        stop: &AtomicBool,
    ) -> Result<Vec<Capture>> {
        Ok(self.render_unflushed(opt, progress, stop)?.0)
    }

    /// As [`Plan::render_all_until`], with the units finished since the checkpoint's last append,
    /// which a completed render does not write (its caller deletes the checkpoint next).
    fn render_unflushed(
        &self,
        opt: &RenderOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
        stop: &AtomicBool,
    ) -> Result<(Vec<Capture>, Option<Unflushed>)> {
        let mut caps = self.empty_captures(opt.spp, opt.seed, opt.shard);
        let unflushed = self.run(opt, progress, stop, Some(&mut caps))?;
        caps.iter_mut().for_each(|c| self.finish(c));
        Ok((caps, unflushed))
    }

    /// As [`Plan::render_all_until`], then writes capture k to `outs[k]` with `write` (none when `outs`
    /// is empty) and removes `opt.checkpoint`: once the captures are stored, a stale checkpoint could
    /// only mislead a later resume. An interrupted render, or one whose write fails, keeps its
    /// checkpoint with every unit it finished, so a resume renders nothing twice.
    pub fn render_stored(
        &self,
        opt: &RenderOptions,
        outs: &[PathBuf],
        write: &dyn Fn(&Path, &Capture) -> Result<()>,
        progress: &(dyn Fn(usize, usize) + Sync),
        stop: &AtomicBool,
    ) -> Result<Vec<Capture>> {
        if !outs.is_empty() && outs.len() != self.ratios.len() {
            return Err(Error::param(format!(
                "{} outputs for a render of {} capture{}",
                outs.len(),
                self.ratios.len(),
                if self.ratios.len() == 1 { "" } else { "s" }
            )));
        }
        let (caps, unflushed) = self.render_unflushed(opt, progress, stop)?;
        if let Err(e) = outs
            .iter()
            .zip(&caps)
            .try_for_each(|(out, cap)| write(out, cap))
        {
            // The write's own error says more than a failed append after it.
            let _ = unflushed.map(Unflushed::append);
            return Err(e);
        }
        if let Some(ckpt) = &opt.checkpoint {
            // Failing to remove it is harmless: its header still matches only this render.
            let _ = std::fs::remove_file(ckpt);
        }
        Ok(caps)
    }

    /// The spp that fills 90 % of `budget_s` seconds for the units of `shard` on the current rayon
    /// pool, timed on a short pilot run of a few units at 8 spp.
    pub fn spp_for_budget(&self, budget_s: f64, shard: Option<(usize, usize)>) -> Result<u64> {
        time_budget(budget_s)?;
        let n_units = self.shard_units(shard).len();
        let threads = rayon::current_num_threads();
        let pilot: Vec<usize> = (0..threads * 2)
            .map(|k| k * self.n_units() / (threads * 2))
            .collect();
        let pilot_spp = 8;
        let t0 = Instant::now();
        pilot.par_iter().for_each(|&u| {
            self.render_unit(u, pilot_spp, u64::MAX);
        });
        // CPU seconds per unit (a tile of traced points) and sample.
        let per_unit_spp =
            t0.elapsed().as_secs_f64() * threads as f64 / (pilot.len() as f64 * pilot_spp as f64);
        let spp = (0.9 * budget_s * threads as f64 / (n_units as f64 * per_unit_spp)).floor();
        Ok((spp as u64).clamp(1, MAX_SPP))
    }

    /// A sweep's several captures are refused before any work rather than dropped after it.
    fn plain_only(&self) -> Result<()> {
        match self.albedos.len() {
            0 => Ok(()),
            n => Err(Error::param(format!(
                "an albedo sweep renders {n} captures: render_all_until or assemble_all returns them"
            ))),
        }
    }

    /// One empty capture per albedo, each with its `scene_info`.
    fn empty_captures(&self, spp: u64, seed: u64, shard: Option<(usize, usize)>) -> Vec<Capture> {
        self.scene_infos(spp, seed, shard)
            .into_iter()
            .map(|info| self.empty_capture(info))
            .collect()
    }

    /// The `scene_info` of each capture this plan renders (one per albedo of a sweep): what a
    /// finished capture must hold to be this render's.
    pub fn scene_infos(&self, spp: u64, seed: u64, shard: Option<(usize, usize)>) -> Vec<String> {
        if self.albedos.is_empty() {
            return vec![scene_info(self.scene, spp, seed, shard)];
        }
        // The sweep's lines go before the shard line, which merging strips; the scene's own text (in
        // the info's head) may hold anything, so the head is rendered without a shard.
        let head = scene_info(self.scene, spp, seed, None);
        let shard = shard.map_or(String::new(), shard_line);
        self.albedos
            .iter()
            .map(|a| {
                format!(
                    "{head}{SWEEP_KEY}{:?}\n{ALBEDO_KEY}{a:?}\n{shard}",
                    self.albedos
                )
            })
            .collect()
    }

    /// Renders shard `opt.shard` into its checkpoint alone, which holds every unit of the shard when
    /// this returns: a part for [`Plan::assemble`]. Unlike a part of [`Plan::render`] it holds only its
    /// own histograms, and nothing is written twice. A complete checkpoint returns at once.
    pub fn render_part(
        &self,
        opt: &RenderOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
        stop: &AtomicBool,
    ) -> Result<()> {
        if opt.checkpoint.is_none() || opt.shard.is_none() {
            return Err(Error::param(
                "a part render needs a shard and a checkpoint file to hold it",
            ));
        }
        self.run(opt, progress, stop, None).map(|_| ())
    }

    /// The capture an unsharded render of `spp` and `seed` gives, bit for bit, from the checkpoints
    /// that [`Plan::render_part`] completed: `parts[i]` holds shard (i, parts.len()). A part of another
    /// render, or one with units missing, is refused naming its file.
    pub fn assemble(&self, spp: u64, seed: u64, parts: &[PathBuf]) -> Result<Capture> {
        self.plain_only()?;
        Ok(self.assemble_all(spp, seed, parts)?.remove(0))
    }

    /// As [`Plan::assemble`], with one capture per albedo of a sweep.
    pub fn assemble_all(&self, spp: u64, seed: u64, parts: &[PathBuf]) -> Result<Vec<Capture>> {
        let n = parts.len();
        if n == 0 {
            return Err(Error::param("assembling needs at least one part"));
        }
        let mut caps = self.empty_captures(spp, seed, None);
        let mut mine = vec![false; self.n_units()];
        for (i, path) in parts.iter().enumerate() {
            let shard = Some((i, n));
            let units = self.shard_units(shard);
            units.iter().for_each(|&u| mine[u] = true);
            let mut found = 0;
            let key = self.key(spp, seed, shard);
            read_checkpoint(path, &key, self.unit_len(), self.n_units(), |u, buf| {
                // Each unit once: a unit of another shard or a repeat is not stored again.
                if std::mem::replace(&mut mine[u], false) {
                    self.store(&mut caps, u, buf);
                    found += 1;
                }
            })?
            .ok_or_else(|| {
                Error::io(
                    path,
                    std::io::Error::new(std::io::ErrorKind::NotFound, "no such part"),
                )
            })?;
            if found != units.len() {
                return Err(Error::format(
                    path,
                    format!(
                        "part {i}/{n} is incomplete: {found} of its {} units",
                        units.len()
                    ),
                ));
            }
        }
        caps.iter_mut().for_each(|c| self.finish(c));
        Ok(caps)
    }

    /// The render key of this plan's renders: [`render_key`], with the albedos of a sweep.
    pub fn key(&self, spp: u64, seed: u64, shard: Option<(usize, usize)>) -> String {
        let key = render_key(self.scene, spp, seed, shard);
        if self.albedos.is_empty() {
            key
        } else {
            format!("{key}\nrender.albedo_sweep = {:?}", self.albedos)
        }
    }

    /// Refuses options this plan cannot render (spp out of range, a shard beyond its work units)
    /// before any work: an executor checks them once rather than in every task.
    pub fn check(&self, opt: &RenderOptions) -> Result<()> {
        if !(1..=MAX_SPP).contains(&opt.spp) {
            return Err(Error::param(format!(
                "spp must be between 1 and {MAX_SPP}, got {}",
                opt.spp
            )));
        }
        if let Some((i, n)) = opt.shard {
            check_shard(i, n).map_err(Error::param)?;
            // Shard i holds units i, i + n, …: more shards than units would leave some empty.
            if n > self.n_units() {
                return Err(Error::param(format!(
                    "shard {i}/{n}: this render has {} work units (tiles of traced points), so at most {} shards",
                    self.n_units(),
                    self.n_units()
                )));
            }
        }
        Ok(())
    }

    /// Renders the units of `opt.shard` that its checkpoint does not hold yet, into `h` when given.
    /// A capture's checkpoint is deleted by its caller once the capture is written, so the units
    /// left pending by the interval are appended only when the render stops early (to resume from) or
    /// when there is no `h` (the checkpoint is then the result).
    fn run(
        &self,
        opt: &RenderOptions,
        progress: &(dyn Fn(usize, usize) + Sync),
        stop: &AtomicBool,
        mut h: Option<&mut [Capture]>,
    ) -> Result<Option<Unflushed>> {
        self.check(opt)?;
        let units = self.shard_units(opt.shard);
        let total = units.len();
        let mut done = vec![false; self.n_units()];
        let mut mine = vec![false; self.n_units()];
        units.iter().for_each(|&u| mine[u] = true);
        // The units the checkpoint already holds are done; a capture's are stored as they are read.
        let ckpt = match &opt.checkpoint {
            Some(p) => Some(Checkpoint::open(
                p,
                &self.key(opt.spp, opt.seed, opt.shard),
                self.unit_len(),
                self.n_units(),
                |u, buf| {
                    if mine[u] {
                        if let Some(h) = h.as_deref_mut() {
                            self.store(h, u, buf);
                        }
                        done[u] = true;
                    }
                },
            )?),
            None => None,
        };
        let todo: Vec<usize> = units.iter().copied().filter(|u| !done[*u]).collect();
        progress(total - todo.len(), total);
        let part = h.is_none();
        // Each finished unit is stored at once, and the first to finish after the interval appends
        // everything pending to the checkpoint: the interval is honoured to within one unit.
        struct Shared<'c> {
            h: Option<&'c mut [Capture]>,
            done: usize,
            pending: Vec<(usize, Vec<f32>)>,
            last: Instant,
            ckpt: Option<Checkpoint>,
        }
        let shared = Mutex::new(Shared {
            h,
            done: total - todo.len(),
            pending: Vec::new(),
            last: Instant::now(),
            ckpt,
        });
        let result = todo.par_iter().try_for_each(|&u| -> Result<()> {
            if stop.load(Ordering::Relaxed) {
                return Err(Error::param("render stopped"));
            }
            let buf = self.render_unit(u, opt.spp, opt.seed);
            let mut guard = shared.lock().unwrap_or_else(|e| e.into_inner());
            let s = &mut *guard;
            if let Some(h) = s.h.as_deref_mut() {
                self.store(h, u, &buf);
            }
            s.done += 1;
            progress(s.done, total);
            if let Some(c) = s.ckpt.as_mut() {
                s.pending.push((u, buf));
                if s.last.elapsed() >= opt.checkpoint_every {
                    c.append(&s.pending)?;
                    s.pending.clear();
                    s.last = Instant::now();
                }
            }
            Ok(())
        });
        let s = shared.into_inner().unwrap_or_else(|e| e.into_inner());
        let unflushed = s.ckpt.map(|ckpt| Unflushed {
            ckpt,
            pending: s.pending,
        });
        match unflushed {
            Some(u) if result.is_err() || part => {
                let flushed = u.append();
                // A stop's own error says more than a failed flush after it.
                result.and(flushed).map(|_| None)
            }
            u => result.map(|_| u),
        }
    }

    /// What a capture gets once all its units are in: the devices' radiometry, if the scene asks.
    fn finish(&self, cap: &mut Capture) {
        let spec = &self.scene.capture;
        if let (true, Some(laser), Some(spad)) =
            (spec.device_radiometry, spec.laser_xyz, spec.sensor_xyz)
        {
            cap.apply_device_radiometry(laser, spad);
        }
    }

    fn unit_len(&self) -> usize {
        self.ratios.len()
            * self.n_targets()
            * self.scene.capture.time.bins
            * self.tile.0
            * self.tile.1
    }
}

/// The capture files a render to `out` writes: `out`, or one per albedo of a sweep ([`sweep_output`]).
pub fn render_outputs(out: &Path, albedos: Option<&[f64]>) -> Vec<PathBuf> {
    match albedos {
        None => vec![out.to_path_buf()],
        Some(a) => a.iter().map(|&al| sweep_output(out, al)).collect(),
    }
}

/// Where a sweep's capture of `albedo` goes when the render's output is `out`: `-albedo<α>` before the
/// extension (`z.h5` → `z-albedo0.5.h5`; a shard part's `z.part0of4.h5` → `z.part0of4-albedo0.5.h5`).
pub fn sweep_output(out: &Path, albedo: f64) -> PathBuf {
    let stem = out
        .file_stem()
        .map(|s| s.to_string_lossy())
        .unwrap_or_default();
    // Below 1e-4 in exponent form: Display writes 1e-300 with 300 digits, too long for a file name.
    let albedo = match albedo {
        a if a == 0.0 || a.abs() >= 1e-4 => format!("{a}"),
        a => format!("{a:e}"),
    };
    let name = match out.extension() {
        Some(ext) => format!("{stem}-albedo{albedo}.{}", ext.to_string_lossy()),
        None => format!("{stem}-albedo{albedo}"),
    };
    out.with_file_name(name)
}

/// YAML for the capture's `scene_info`: the scene file, spp, seed, murk version, the overrides and the
/// resolved scene (and the shard of a part).
pub fn scene_info(scene: &Scene, spp: u64, seed: u64, shard: Option<(usize, usize)>) -> String {
    let mut s = format!(
        "generator: murk render\nmurk_version: {}\nscene_file: {:?}\nspp: {spp}\nseed: {seed}\n",
        env!("CARGO_PKG_VERSION"),
        scene.file_name
    );
    if !scene.overrides.is_empty() {
        s.push_str("overrides:\n");
        for o in &scene.overrides {
            s.push_str(&format!("- {o:?}\n"));
        }
    }
    s.push_str("scene: |\n");
    for line in scene.source.lines() {
        s.push_str("  ");
        s.push_str(line);
        s.push('\n');
    }
    if let Some(shard) = shard {
        s.push_str(&shard_line(shard));
    }
    s
}

const SHARD_KEY: &str = "shard: ";

/// The last line of a shard's `scene_info`, which merging strips.
fn shard_line((i, n): (usize, usize)) -> String {
    format!("{SHARD_KEY}{i}/{n}\n")
}

/// A sweep's albedos, and the one a capture of it has, in its `scene_info`.
const SWEEP_KEY: &str = "albedo_sweep: ";
const ALBEDO_KEY: &str = "albedo: ";

/// The one rule for shard `i` of `n` (render, merge and the CLI's parser): 0 ≤ i < n.
pub fn check_shard(i: usize, n: usize) -> std::result::Result<(), String> {
    match n > 0 && i < n {
        true => Ok(()),
        false => Err(format!("shard {i}/{n}: need 0 ≤ i < N")),
    }
}

/// Sums shard parts into the capture an unsharded render gives, bit for bit: shards own disjoint
/// histograms, so each sum adds exact zeros. Two parts with signal in one histogram (a part renamed
/// or relabelled as another shard) are refused, as is a part whose wall points or device legs
/// differ from the first's.
pub fn merge(parts: &[(PathBuf, Capture)]) -> Result<Capture> {
    let Some((p0, first)) = parts.first() else {
        return Err(Error::param("merge needs at least one part"));
    };
    let split = |path: &Path, c: &Capture| -> Result<(String, usize, usize)> {
        let mut base = String::new();
        let mut shard = None;
        for line in c.scene_info.lines() {
            match line.strip_prefix(SHARD_KEY) {
                Some(r) => {
                    let parsed = r
                        .split_once('/')
                        .and_then(|(i, n)| i.parse().ok().zip(n.parse().ok()));
                    shard = Some(parsed.ok_or_else(|| {
                        Error::format(path, format!("scene_info's shard '{r}' is not i/N"))
                    })?);
                }
                None => {
                    base.push_str(line);
                    base.push('\n');
                }
            }
        }
        let (i, n) = shard.ok_or_else(|| {
            Error::format(
                path,
                "not a shard of `murk render --shard` (no `shard: i/N` in scene_info)",
            )
        })?;
        check_shard(i, n).map_err(|e| Error::format(path, format!("{e} in scene_info")))?;
        // Every shard holds at least one histogram: checked before anything is sized by n.
        if n > c.n_hist() {
            return Err(Error::format(
                path,
                format!(
                    "shard {i}/{n} in scene_info, but the capture has only {} histograms to shard",
                    c.n_hist()
                ),
            ));
        }
        Ok((base, i, n))
    };
    let (base, _, n) = split(p0, first)?;
    let mut seen = vec![false; n];
    let mut owner: Vec<Option<usize>> = vec![None; first.n_hist()];
    let mut out = first.clone();
    out.h.iter_mut().for_each(|v| *v = 0.0);
    out.scene_info = base.clone();
    for (path, c) in parts {
        let (b, i, k) = split(path, c)?;
        if b != base
            || k != n
            || c.h.len() != out.h.len()
            || !c.time.same_as_stored(&out.time)
            || c.pairing != out.pairing
            || c.illum.points != first.illum.points
            || c.sensor.points != first.sensor.points
            || (
                c.laser_xyz,
                c.sensor_xyz,
                c.t_accounts_first_and_last_bounces,
            ) != (
                first.laser_xyz,
                first.sensor_xyz,
                first.t_accounts_first_and_last_bounces,
            )
        {
            return Err(Error::format(path, "belongs to a different render (scene, spp, seed, shard count or layout differ from the first part)"));
        }
        if std::mem::replace(&mut seen[i], true) {
            return Err(Error::format(path, format!("shard {i}/{n} given twice")));
        }
        let bins = out.time.bins;
        for (h, (o, v)) in out.h.chunks_mut(bins).zip(c.h.chunks(bins)).enumerate() {
            if v.iter().any(|x| *x != 0.0) {
                if let Some(other) = owner[h].replace(i) {
                    return Err(Error::format(
                        path,
                        format!(
                            "shard {i}/{n} has signal in histogram {h}, which shard {other}/{n} holds too: one of them is not the shard it says"
                        ),
                    ));
                }
            }
            o.iter_mut().zip(v).for_each(|(o, v)| *o += v);
        }
    }
    if let Some(missing) = seen.iter().position(|s| !s) {
        let given: Vec<String> = parts.iter().map(|(p, _)| p.display().to_string()).collect();
        return Err(Error::param(format!(
            "shard {missing}/{n} is missing: the parts given are {}",
            given.join(", ")
        )));
    }
    Ok(out)
}

/// Everything that determines the rendered numbers, as `key = value` lines: the resolved scene, spp,
/// seed, shard and murk version. Two renders with the same key give the same bytes.
pub fn render_key(scene: &Scene, spp: u64, seed: u64, shard: Option<(usize, usize)>) -> String {
    let shard = shard.map_or_else(|| "none".to_string(), |(i, n)| format!("{i}/{n}"));
    format!(
        "{}\nrender.spp_used = {spp}\nrender.seed = {seed}\nrender.shard = {shard}\nrender.estimator = {ESTIMATOR_REVISION}\nmurk_version = {}",
        scene.resolved,
        env!("CARGO_PKG_VERSION")
    )
}

/// The estimator's revision, raised whenever a scene, spp and seed render other bytes than before (2:
/// anisotropic fog's shared-tail weights and target lobe), so that checkpoints and the study's finished
/// renders made before are refused or rendered again rather than mixed in. A change that moves only
/// some scenes' bytes names itself in those scenes' resolved key instead, so the others keep theirs
/// (the forward lobe's default share: `render.target_lobe_default`, set in `Scene::load`).
pub const ESTIMATOR_REVISION: u32 = 2;

/// FNV-1a, 64 bits: a short name for a render key.
pub fn fingerprint(key: &str) -> u64 {
    fingerprint_bytes(key.bytes())
}

/// FNV-1a, 64 bits, of any bytes.
pub(crate) fn fingerprint_bytes(bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes.into_iter().fold(0xcbf2_9ce4_8422_2325u64, |h, b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

/// An append-only file of finished units: a header (magic, fingerprint, unit length, key length, the
/// render key), then records of (unit index: u64, values: f32 × unit length, checksum: u64),
/// little-endian. The valid prefix ends at the first record cut short by a kill or whose checksum fails
/// (a crash can leave zeros where data was not yet written; a disk can flip bits): the units from there
/// on are rendered again, so a resumed capture is still exact. A key that differs is refused, naming
/// what differs.
struct Checkpoint {
    file: std::fs::File,
    path: PathBuf,
    unit_len: usize,
}

const MAGIC: &[u8; 8] = b"MURKCKP3";

/// Bytes of one record: unit index, values and checksum.
fn record_len(unit_len: usize) -> usize {
    8 + 4 * unit_len + 8
}

/// A record's checksum over its index and values: FNV-1a over 8-byte words (a tail zero-padded), fast
/// enough to check a whole capture's checkpoint as it is read.
fn record_sum(bytes: &[u8]) -> u64 {
    let mut chunks = bytes.chunks_exact(8);
    let word = |c: &[u8]| {
        let mut w = [0u8; 8];
        w[..c.len()].copy_from_slice(c);
        u64::from_le_bytes(w)
    };
    let h = chunks.by_ref().fold(0xcbf2_9ce4_8422_2325u64, |h, c| {
        (h ^ word(c)).wrapping_mul(0x0100_0000_01b3)
    });
    (h ^ word(chunks.remainder())).wrapping_mul(0x0100_0000_01b3)
}

/// A checkpoint's header: magic, fingerprint, unit length, key length and the render key.
fn header(key: &str, unit_len: usize) -> Vec<u8> {
    let mut header = Vec::with_capacity(32 + key.len());
    header.extend_from_slice(MAGIC);
    header.extend_from_slice(&fingerprint(key).to_le_bytes());
    header.extend_from_slice(&(unit_len as u64).to_le_bytes());
    header.extend_from_slice(&(key.len() as u64).to_le_bytes());
    header.extend_from_slice(key.as_bytes());
    header
}

/// Calls `unit(u, values)` for each whole record of the checkpoint at `path`, after checking that its
/// header is this render's; returns the length of the valid prefix, or `None` when there is no file.
/// A unit index beyond `units` in a record whose checksum holds is a format error.
fn read_checkpoint(
    path: &Path,
    key: &str,
    unit_len: usize,
    units: usize,
    mut unit: impl FnMut(usize, &[f32]),
) -> Result<Option<u64>> {
    if matches!(std::fs::metadata(path), Err(e) if e.kind() == std::io::ErrorKind::NotFound) {
        return Ok(None);
    }
    // A regular file only (a FIFO would block, a device never end), and no larger than this
    // render's header and every unit once: checked before reading it into memory.
    let mut f = murk_core::open_input(path)?;
    let header = header(key, unit_len);
    let rec = record_len(unit_len);
    let most = (units as u64 + 1) * rec as u64 + header.len() as u64;
    let mut bytes = Vec::new();
    (&mut f)
        .take(most + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    // Empty, or cut inside this render's own header by a kill: nothing was recorded yet.
    if header.starts_with(&bytes) {
        return Ok(Some(0));
    }
    if !bytes.starts_with(&header) {
        return Err(Error::format(path, refusal(&bytes, key)));
    }
    if bytes.len() as u64 > most {
        return Err(Error::format(
            path,
            format!("more bytes than a checkpoint of this render's {units} units holds"),
        ));
    }
    let mut vals = vec![0f32; unit_len];
    let mut off = header.len();
    while off + rec <= bytes.len() {
        let (body, sum) = bytes[off..off + rec].split_at(rec - 8);
        if record_sum(body) != u64::from_le_bytes(sum.try_into().expect("8 bytes")) {
            break;
        }
        let u = u64::from_le_bytes(body[..8].try_into().expect("8 bytes"));
        let u = usize::try_from(u)
            .ok()
            .filter(|&u| u < units)
            .ok_or_else(|| {
                Error::format(
                    path,
                    format!("unit {u} recorded, but the render has {units}"),
                )
            })?;
        for (v, b) in vals.iter_mut().zip(body[8..].chunks_exact(4)) {
            *v = f32::from_le_bytes(b.try_into().expect("4 bytes"));
        }
        unit(u, &vals);
        off += rec;
    }
    Ok(Some(off as u64))
}

impl Checkpoint {
    /// Opens (or starts) the checkpoint at `path` for appending, passing each unit it holds to `unit`.
    fn open(
        path: &Path,
        key: &str,
        unit_len: usize,
        units: usize,
        unit: impl FnMut(usize, &[f32]),
    ) -> Result<Self> {
        let io = |e| Error::io(path, e);
        let valid_len = read_checkpoint(path, key, unit_len, units, unit)?.unwrap_or(0);
        let mut file = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(path)
            .map_err(io)?;
        if valid_len == 0 {
            file.set_len(0).map_err(io)?;
            file.write_all(&header(key, unit_len)).map_err(io)?;
        } else {
            // Drop a torn trailing record so appends stay aligned.
            file.set_len(valid_len).map_err(io)?;
        }
        Ok(Checkpoint {
            file,
            path: path.to_path_buf(),
            unit_len,
        })
    }

    fn append(&mut self, recs: &[(usize, Vec<f32>)]) -> Result<()> {
        let mut buf = Vec::with_capacity(recs.len() * record_len(self.unit_len));
        for (u, vals) in recs {
            let start = buf.len();
            buf.extend_from_slice(&(*u as u64).to_le_bytes());
            vals.iter()
                .for_each(|v| buf.extend_from_slice(&v.to_le_bytes()));
            let sum = record_sum(&buf[start..]);
            buf.extend_from_slice(&sum.to_le_bytes());
        }
        let io = |e| Error::io(&self.path, e);
        let before = self.file.metadata().map_err(io)?.len();
        let written = self
            .file
            .write_all(&buf)
            .and_then(|_| self.file.sync_data());
        if written.is_err() {
            // A torn record would misalign every later append (a retry after a failed write
            // appends the same units again), so the file goes back to its last whole record.
            let _ = self.file.set_len(before);
        }
        written.map_err(io)
    }
}

/// A checkpoint and the finished units not yet appended to it.
struct Unflushed {
    ckpt: Checkpoint,
    pending: Vec<(usize, Vec<f32>)>,
}

impl Unflushed {
    fn append(mut self) -> Result<()> {
        self.ckpt.append(&self.pending)
    }
}

/// Why a checkpoint's header does not match this render, naming the keys that differ where it can.
fn refusal(bytes: &[u8], key: &str) -> String {
    let theirs = (bytes.len() >= 32 && bytes[..8] == MAGIC[..])
        .then(|| u64::from_le_bytes(bytes[24..32].try_into().expect("8 bytes")) as usize)
        .and_then(|n| bytes.get(32..32usize.checked_add(n)?))
        .and_then(|k| std::str::from_utf8(k).ok());
    let what = match theirs {
        Some(k) => {
            let diffs = crate::overrides::differences(k, key, 4);
            if diffs.is_empty() {
                "its layout differs".to_string()
            } else {
                diffs.join("; ")
            }
        }
        None if bytes.starts_with(MAGIC) => {
            return "damaged checkpoint (its header is cut short); delete it to start afresh".into()
        }
        None => "it is not a checkpoint of this murk version".to_string(),
    };
    format!("checkpoint of a different render ({what}); delete it to start afresh")
}
