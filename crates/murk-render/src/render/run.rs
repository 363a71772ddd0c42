//! Rendering a plan's units in parallel: the options of a render, the loop that renders the units a
//! checkpoint does not hold yet, and the spp that fits a time budget.

use super::checkpoint::{Checkpoint, Unflushed};
use super::shard::check_shard;
use super::Plan;
use murk_core::{Capture, Error, Result};
use rayon::prelude::*;
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

impl<'a> Plan<'a> {
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
}
