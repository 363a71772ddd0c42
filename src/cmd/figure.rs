//! `murk figure real`: the paper's real-data comparison (its Fig. 5), built by
//! `murk_study::figure_real`.

use crate::cmd::progress::say;
use clap::{Args, ValueEnum};
use std::path::PathBuf;

#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Which {
    /// CDT vs Phasor Fields on the five real captures behind a 2.54 cm foam slab.
    Real,
}

#[derive(Args)]
#[command(after_help = "Example:\n  \
murk figure real --data ../shared/data/real/cdt_lindell2020 --out fig-real/")]
pub struct FigureArgs {
    pub which: Which,
    /// Folder with letter_s.mat, mannequin.mat, letter_t.mat, cones.mat, letters_ut.mat.
    #[arg(long)]
    pub data: PathBuf,
    /// Output folder (grid.png, index.html).
    #[arg(long)]
    pub out: PathBuf,
    /// Timed runs per reconstruction (the median is reported), 1 to 1000.
    #[arg(long, default_value_t = 5, value_parser = clap::value_parser!(u16).range(1..=1000))]
    pub runs: u16,
}

pub fn run(a: FigureArgs, quiet: bool) -> anyhow::Result<()> {
    let Which::Real = a.which;
    let index = murk_study::figure_real(&a.data, &a.out, a.runs.into(), &|line| say(quiet, line))?;
    say(quiet, format!("wrote {}", index.display()));
    Ok(())
}
