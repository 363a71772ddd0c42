//! `murk demo`: the whole pipeline on a built-in scene, in seconds, with pictures to look at.

use crate::cmd::progress::{say, Bar};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
#[command(after_help = "Examples:\n  \
murk demo                      # writes murk-demo/ (capture, volume, pictures, index.html)\n  \
murk demo --out /tmp/z-demo")]
pub struct DemoArgs {
    /// Folder for the capture, the volume, the pictures and index.html.
    #[arg(long, default_value = "murk-demo")]
    pub out: PathBuf,
}

pub fn run(a: DemoArgs, quiet: bool) -> anyhow::Result<()> {
    let bar = Bar::new("reconstruct", quiet);
    let d = murk_study::demo(&a.out, &bar)?;
    bar.finish();
    say(quiet, format!("murk demo: hidden Z at {} m; reconstruction peak at depth {:.3} m ({:.2} s synthesis, {:.2} s reconstruction)", murk_study::demo::LETTER_DEPTH_M, d.peak_depth_m, d.synth_s, d.recon_s));
    say(quiet, format!("  capture  {}", d.capture.display()));
    say(quiet, format!("  volume   {}", d.volume.display()));
    say(quiet, format!("  pictures {}", d.index.display()));
    Ok(())
}
