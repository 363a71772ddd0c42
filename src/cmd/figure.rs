//! `murk figure real`: the paper's real-data comparison (its Fig. 6), built by
//! `murk_study::figure_real`; `murk figure media`: the foam captures by every method, built by
//! `murk_study::figure_media`.

use crate::cmd::progress::say;
use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Which {
    /// CDT vs Phasor Fields on the five real captures behind a 2.54 cm foam slab.
    Real,
    /// Every foam capture in --data (the BMM letter T inside foam, the CDT captures behind it) by
    /// BMM, CDT, PF without and with its medium-aware path, LCT and f-k.
    Media,
}

#[derive(Args)]
#[command(after_help = "Examples:\n  \
murk figure real --data ../shared/data/real/cdt_lindell2020 --out fig-real/\n  \
murk figure media --data ../shared/data/real/bmm_du2022 --out fig-media/\n\n\
media reads the files of --data named as the BMM captures (2cmFoam_LambertianT_7cmFoam.mat, …) or the\n\
CDT ones (letter_s.mat, …), and writes grid.png (a row per capture, a column per method), depths.csv\n\
(each method's surface depth per capture) and index.html. docs/import.md explains how to read them.")]
pub struct FigureArgs {
    pub which: Which,
    /// real: folder with letter_s.mat, mannequin.mat, letter_t.mat, cones.mat, letters_ut.mat;
    /// media: folder with BMM or CDT captures under their published names.
    #[arg(long)]
    pub data: PathBuf,
    /// Output folder (grid.png, index.html; media also depths.csv).
    #[arg(long)]
    pub out: PathBuf,
    /// real: timed runs per reconstruction (the median is reported), 1 to 1000 (default 5).
    #[arg(long, value_parser = clap::value_parser!(u16).range(1..=1000))]
    pub runs: Option<u16>,
}

pub fn run(a: FigureArgs, quiet: bool) -> anyhow::Result<()> {
    let line = |l: &str| say(quiet, l);
    let index = match a.which {
        Which::Real => murk_study::figure_real(&a.data, &a.out, a.runs.unwrap_or(5).into(), &line)?,
        Which::Media if a.runs.is_some() => {
            anyhow::bail!(
                "--runs applies to figure real: figure media does not time its reconstructions"
            )
        }
        Which::Media => murk_study::figure_media(&a.data, &a.out, &line)?,
    };
    say(quiet, format!("wrote {}", index.display()));
    Ok(())
}
