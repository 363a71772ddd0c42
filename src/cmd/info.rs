//! `murk info`: what a capture file holds.

use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
#[command(after_help = "Examples:\n  \
murk info capture.h5\n  \
murk info capture.h5 | grep 'window end'   # how much signal the window's last bins still carry")]
pub struct InfoArgs {
    /// A y-tal HDF5 capture (.h5 / .hdf5).
    pub file: PathBuf,
}

pub fn run(a: InfoArgs) -> anyhow::Result<()> {
    let cap = murk_io::read_capture(&a.file)?;
    println!("{}", murk_io::describe(&cap).join("\n"));
    Ok(())
}
