//! `murk info`: what a capture file holds.

use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
#[command(after_help = "Examples:\n  \
murk info capture.h5\n  \
murk info capture.h5 | grep 'window end'   # how much signal the window's last bins still carry\n  \
murk info truth.h5                           # a ground truth: lattice, depths, objects, bounds")]
pub struct InfoArgs {
    /// A y-tal HDF5 capture (.h5 / .hdf5), or a ground truth that `murk render --truth` wrote.
    pub file: PathBuf,
}

pub fn run(a: InfoArgs) -> anyhow::Result<()> {
    let lines = match murk_io::read_capture(&a.file) {
        Ok(cap) => murk_io::describe(&cap),
        // Not a capture: a ground truth is described, or its own fault named; anything else keeps
        // the capture's error.
        Err(_) if murk_io::looks_like_truth(&a.file) => {
            murk_io::describe_truth(&murk_io::read_truth_h5(&a.file)?)
        }
        Err(e) => return Err(e.into()),
    };
    println!("{}", lines.join("\n"));
    Ok(())
}
