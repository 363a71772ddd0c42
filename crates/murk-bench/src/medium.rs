//! `murk-bench --medium CAPTURE`: what the medium-aware path costs on a capture in a medium, as
//! `murk reconstruct` runs it (plan and run together, the default volume): the plain path (removal and
//! depth search off), the default path (detection, the fitted removal, the depth search and the band
//! it keeps), the medium's estimate (`murk medium`: its table of renders and the fit; and again with
//! its table read back from a `--table-cache` folder) and `--medium-removal model` (that estimate, the
//! prediction it makes and the reconstruction that subtracts it), alternated run by run so that the
//! machine's drift meets each alike.

use crate::say;
use anyhow::Context;
use murk_core::NoProgress;
use murk_methods::{Method, Options, Request};
use murk_recon::medium::{DepthSearch, MediumAware, MediumRemoval};
use std::path::Path;
use std::time::Instant;

/// `tables`: a folder that keeps the tables (`--medium-tables`); the estimate that renders one is
/// then not timed.
pub fn run(path: &Path, tables: Option<&Path>, runs: usize, quiet: bool) -> anyhow::Result<()> {
    let ctx = || path.display().to_string();
    let cap = murk_io::read_capture(path)?;
    let method = Method::named("pf", &Options::default()).with_context(ctx)?;
    let aware = Request::new(method);
    let plain = Request {
        medium: MediumAware {
            removal: MediumRemoval::Off,
            depth_search: DepthSearch::Off,
        },
        ..aware
    };
    let model = Request {
        medium: MediumAware {
            removal: MediumRemoval::Model,
            ..aware.medium
        },
        ..aware
    };
    let estimate = murk_medium::EstimateOptions::default();
    // The estimate once more with its table kept in a folder (`--table-cache`): written by the first
    // run, read back by the others, so its median is what a capture of a known geometry costs.
    let cache = tables.map_or_else(
        || std::env::temp_dir().join(format!("murk-bench-tables-{}", std::process::id())),
        Path::to_path_buf,
    );
    let cached = murk_medium::EstimateOptions {
        table_cache: Some(cache.clone()),
        ..murk_medium::EstimateOptions::default()
    };
    let t0 = Instant::now();
    murk_medium::estimate(&cap, &cached, &|_, _| {}).with_context(ctx)?;
    let first = t0.elapsed().as_secs_f64();
    // … and with the medium-only bins' end given (`--until`): no depth search, the fit alone.
    let until = murk_medium::EstimateOptions {
        until_m: Some(murk_medium::fit::scene_onset_m(
            &cap,
            &murk_medium::fit::onset_search(&cap)?,
        )?),
        ..cached.clone()
    };
    let (mut t_plain, mut t_aware, mut t_estimate) = (Vec::new(), Vec::new(), Vec::new());
    let (mut t_cached, mut t_until, mut t_model) = (Vec::new(), Vec::new(), Vec::new());
    // `murk reconstruct --medium-removal model` with the table kept: the estimate, its prediction and
    // the reconstruction that subtracts it (and takes the estimate's depth search).
    let removal_model = || -> anyhow::Result<()> {
        let murk_medium::Outcome::Fitted(e) = murk_medium::estimate(&cap, &cached, &|_, _| {})?
        else {
            anyhow::bail!("{}: no medium detected", ctx());
        };
        let given = murk_methods::MediumGiven {
            predicted: Some(murk_medium::model::for_removal(&cap, None, None, Some(&e))?),
            density: None,
            searched: e.searched,
        };
        murk_methods::run_given(cap.clone(), &model, &given, &NoProgress)?;
        Ok(())
    };
    let time = |f: &mut dyn FnMut() -> anyhow::Result<()>, out: &mut Vec<f64>| {
        let t0 = Instant::now();
        f()?;
        out.push(t0.elapsed().as_secs_f64());
        anyhow::Ok(())
    };
    for _ in 0..runs {
        time(
            &mut || Ok(murk_methods::run(cap.clone(), &plain, &NoProgress).map(drop)?),
            &mut t_plain,
        )?;
        time(
            &mut || Ok(murk_methods::run(cap.clone(), &aware, &NoProgress).map(drop)?),
            &mut t_aware,
        )?;
        if tables.is_none() {
            time(
                &mut || Ok(murk_medium::estimate(&cap, &estimate, &|_, _| {}).map(drop)?),
                &mut t_estimate,
            )?;
        }
        time(
            &mut || Ok(murk_medium::estimate(&cap, &cached, &|_, _| {}).map(drop)?),
            &mut t_cached,
        )?;
        time(
            &mut || Ok(murk_medium::estimate(&cap, &until, &|_, _| {}).map(drop)?),
            &mut t_until,
        )?;
        time(&mut || removal_model(), &mut t_model)?;
    }
    if tables.is_none() {
        std::fs::remove_dir_all(&cache).ok();
    }
    let (p, m, e, c, u) = (
        crate::median(&t_plain),
        crate::median(&t_aware),
        crate::median(&t_estimate),
        crate::median(&t_cached),
        crate::median(&t_until),
    );
    let r = crate::median(&t_model);
    say(quiet, format!("medium-aware path on {}:", path.display()));
    say(
        quiet,
        format!("  plain (removal and depth search off): {p:.3} s"),
    );
    say(
        quiet,
        format!(
            "  default (detection, removal, depth search): {m:.3} s ({:+.0} %)",
            100.0 * (m / p - 1.0)
        ),
    );
    if tables.is_none() {
        say(
            quiet,
            format!(
                "  the medium's estimate (table and fit): {e:.3} s ({:.1}× the plain reconstruction)",
                e / p
            ),
        );
    }
    say(
        quiet,
        format!(
            "  the estimate with its table read back (--table-cache; the run that wrote it took {first:.1} s): {c:.3} s ({:.0} % of the plain reconstruction)",
            100.0 * c / p
        ),
    );
    say(
        quiet,
        format!(
            "  … and the medium-only bins' end given (--until: no depth search): {u:.3} s ({:.0} % of the plain reconstruction)",
            100.0 * u / p
        ),
    );
    say(
        quiet,
        format!(
            "  --medium-removal model, the table read back (estimate, prediction, reconstruction): {r:.3} s ({:.0} % of the plain reconstruction)",
            100.0 * r / p
        ),
    );
    Ok(())
}
