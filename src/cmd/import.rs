//! `murk import`: real captures from the public NLOS datasets, or any 3-D array, into y-tal HDF5.
//! The codec, its orientation convention and each dataset's layout live in `murk_io::import`.

use crate::cmd::progress::say;
use clap::builder::PossibleValue;
use clap::{Args, ValueEnum};
use murk_io::import::{BinWidth, Dim, Flip, ImportOptions, Layout, Preset};
use std::path::PathBuf;

/// A `--format` value: one of the library's presets.
#[derive(Clone, Copy, Debug)]
pub struct Format(Preset);

const FORMATS: [Format; 10] = {
    let p = Preset::ALL;
    [
        Format(p[0]),
        Format(p[1]),
        Format(p[2]),
        Format(p[3]),
        Format(p[4]),
        Format(p[5]),
        Format(p[6]),
        Format(p[7]),
        Format(p[8]),
        Format(p[9]),
    ]
};

impl ValueEnum for Format {
    fn value_variants<'a>() -> &'a [Self] {
        &FORMATS
    }

    fn to_possible_value(&self) -> Option<PossibleValue> {
        Some(PossibleValue::new(self.0.name()).help(self.0.summary()))
    }
}

#[derive(Args)]
#[command(after_help = "Examples:\n  \
murk import ../shared/data/real/cdt_lindell2020/letter_s.mat --format cdt --out letter_s.h5\n  \
murk import my_scan.mat --format cdt --wall-size 0.5 --out my_scan.h5\n  \
murk import s_u.mat --format lct --out s_u.h5\n  \
murk import statue/meas_180min.mat --format fk --tof statue/tof.mat --out statue.h5\n  \
murk import bunny_confocal.hdf5 --format znlos --out bunny.h5\n  \
murk import ../shared/data/real/bmm_du2022/4cmFoam_LambertianT_7cmFoam.mat --format bmm --out t4.h5\n  \
murk import scan.npy --axes x,y,t --bin-width-ps 16 --wall-size 1 --confocal --out scan.h5\n  \
murk import data.mat --var capture.hist --axes t,y,x --flip x,y --bin-width-m 0.005 --wall-size 0.6 \
--confocal --t0-bin 40 --out data.h5\n\n\
Scan sides known by file name (cdt): letter_s 0.636 m, mannequin 0.609 m, letters_ut, letter_t and cones 0.7 m;\n\
(bmm): the foam T files 0.2 m (5 cm: 0.1 m, 8 cm: 0.22 m).\n\
Array scans become a confocal grid at z = 0 from −side/2 to +side/2. The presets' arrays are shown by\n\
their reference code with row a top → bottom and column b left → right; row a maps to +y → −y and\n\
column b to +x → −x, so murk's front view (from the wall, +y up, +x left) shows the scene as the\n\
reference does (wu2021's reference plots b upwards and a leftwards: a maps to +x, b to +y).\n\
The generic form's x and y axes run along +x and +y (reverse them with --flip).\n\
Ahn 2019 and Z-NLOS files keep their own wall points. docs/import.md has each dataset's details.")]
pub struct ImportArgs {
    /// A MATLAB .mat (v5 or v7.3), HDF5 or .npy file.
    pub file: PathBuf,
    /// A public dataset's layout (with its published parameters); without it, the generic form
    /// (--var, --axes, --bin-width-*, --wall-size, --confocal) describes the array.
    #[arg(long, value_enum, required_unless_present = "axes")]
    pub format: Option<Format>,
    /// Generic form: the array's name (`a.b`: field b of struct a); not needed for .npy.
    #[arg(long, conflicts_with = "format")]
    pub var: Option<String>,
    /// Generic form: what the array's axes hold, in its shape order (MATLAB's for .mat files),
    /// e.g. t,x,y. x and y indices increase along murk's +x and +y.
    #[arg(long, value_parser = parse_axes, conflicts_with = "format")]
    pub axes: Option<[Dim; 3]>,
    /// Generic form: the scan is confocal (required; non-confocal arrays are not read).
    #[arg(long, conflicts_with = "format")]
    pub confocal: bool,
    /// Full side of the square scan (m), first point to last. Overrides the preset's
    /// (cdt, bmm: by file name; lct, wu2021: twice the file's `width`).
    #[arg(long = "wall-size", value_name = "M")]
    pub wall_size_m: Option<f64>,
    /// Time bin width in picoseconds (converted with c = 3e8 m/s, as the reference codes do).
    #[arg(long, conflicts_with = "bin_width_m")]
    pub bin_width_ps: Option<f64>,
    /// Time bin width in metres of optical path.
    #[arg(long)]
    pub bin_width_m: Option<f64>,
    /// Zero the first N bins (direct light off the wall). Defaults: 600 for lct and lct-transient,
    /// 500 for abp (as their reference codes), 0 otherwise.
    #[arg(long)]
    pub gate_bins: Option<usize>,
    /// Reverse the scan along x, y or both (x,y), on top of the format's orientation.
    #[arg(long, value_parser = parse_flip)]
    pub flip: Option<Flip>,
    /// The bin at path length 0 (the wall); the time axis then starts at −N bins.
    #[arg(long)]
    pub t0_bin: Option<usize>,
    /// fk only: the scene's tof.mat (`tofgrid`, ps per scan point) to rectify the scan with.
    #[arg(long)]
    pub tof: Option<PathBuf>,
    /// Output capture (y-tal HDF5).
    #[arg(long)]
    pub out: PathBuf,
}

fn parse_axes(s: &str) -> Result<[Dim; 3], String> {
    Dim::parse_axes(s).map_err(|e| e.to_string())
}

fn parse_flip(s: &str) -> Result<Flip, String> {
    Flip::parse(s).map_err(|e| e.to_string())
}

impl ImportArgs {
    fn options(&self) -> anyhow::Result<ImportOptions> {
        Ok(ImportOptions {
            layout: Layout::choose(
                self.format.map(|f| f.0),
                self.var.clone(),
                self.axes,
                self.confocal,
            )?,
            wall_size_m: self.wall_size_m,
            bin_width: self
                .bin_width_ps
                .map(BinWidth::Ps)
                .or(self.bin_width_m.map(BinWidth::M)),
            gate_bins: self.gate_bins,
            flip: self.flip.unwrap_or_default(),
            t0_bin: self.t0_bin,
            tof: self.tof.clone(),
        })
    }
}

pub fn run(a: ImportArgs, quiet: bool) -> anyhow::Result<()> {
    let mut inputs = vec![a.file.as_path()];
    inputs.extend(a.tof.as_deref());
    murk_io::check_h5_output(&a.out, &inputs)?;
    let cap = murk_io::import::import(&a.file, &a.options()?)?;
    murk_io::write_capture(&a.out, &cap)?;
    say(quiet, format!("wrote {}", a.out.display()));
    if !quiet {
        println!("{}", murk_io::describe(&cap).join("\n"));
    }
    Ok(())
}
