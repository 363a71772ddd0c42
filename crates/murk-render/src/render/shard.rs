//! Shards: the rule for shard i of N, assembling the checkpoints of part renders and merging the
//! captures of sharded renders into the capture an unsharded render gives, bit for bit.

use super::checkpoint::read_checkpoint;
use super::provenance::SHARD_KEY;
use super::Plan;
use murk_core::{Capture, Error, Result};
use std::path::{Path, PathBuf};

/// The one rule for shard `i` of `n` (render, merge and the CLI's parser): 0 ≤ i < n.
pub fn check_shard(i: usize, n: usize) -> std::result::Result<(), String> {
    match n > 0 && i < n {
        true => Ok(()),
        false => Err(format!("shard {i}/{n}: need 0 ≤ i < N")),
    }
}

impl<'a> Plan<'a> {
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
                format!(
                    "not a shard of a render made with {} (no `shard: i/N` in scene_info)",
                    murk_core::Opt::Shard
                ),
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
