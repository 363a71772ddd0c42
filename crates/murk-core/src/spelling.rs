//! How a message names an option the user can set. The library names it by a neutral [`Opt`]; the
//! text shows it as the front end that serves this process spells it (the command line's flags,
//! `--window-end keep`, or the Python package's keywords, `window_end='keep'`), so a warning or an
//! error that reaches Python never sends its user to a flag they cannot type.

use std::fmt;
use std::sync::OnceLock;

/// The front ends' spellings of options.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Spelling {
    /// `murk`'s flags: `--wall-size`, `--window-end keep`, `--confocal`.
    #[default]
    Cli,
    /// The `murk` Python package's keywords: `wall_size`, `window_end='keep'`, `confocal=True`.
    Python,
}

static FRONT_END: OnceLock<Spelling> = OnceLock::new();

/// Says which front end this process serves; the first call wins. The CLI's `main` and the Python
/// module's initialisation call it before any library call; a plain Rust program gets the CLI's
/// spelling, the documented one.
pub fn set_front_end(spelling: Spelling) {
    let _ = FRONT_END.set(spelling);
}

/// The spelling messages use in this process.
pub fn front_end() -> Spelling {
    FRONT_END.get().copied().unwrap_or_default()
}

/// An option that a message refers the user to, by its neutral name (the Python keyword, the
/// library's field): `Opt::WindowEnd` is `--window-end` on the command line and `window_end` in
/// Python.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Opt {
    Axes,
    BinWidthM,
    BinWidthPs,
    Compensate,
    Confocal,
    DepthSearch,
    Format,
    Gate,
    HeightScale,
    MediumDensity,
    Method,
    MuT,
    Out,
    Shard,
    Tof,
    Var,
    Volume,
    WallSize,
    WindowEnd,
}

impl Opt {
    /// The neutral name: Python's keyword.
    pub fn name(self) -> &'static str {
        match self {
            Opt::Axes => "axes",
            Opt::BinWidthM => "bin_width_m",
            Opt::BinWidthPs => "bin_width_ps",
            Opt::Compensate => "compensate",
            Opt::Confocal => "confocal",
            Opt::DepthSearch => "depth_search",
            Opt::Format => "format",
            Opt::Gate => "gate",
            Opt::HeightScale => "height_scale",
            Opt::MediumDensity => "medium_density",
            Opt::Method => "method",
            Opt::MuT => "mu_t",
            Opt::Out => "out",
            Opt::Shard => "shard",
            Opt::Tof => "tof",
            Opt::Var => "var",
            Opt::Volume => "volume",
            Opt::WallSize => "wall_size",
            Opt::WindowEnd => "window_end",
        }
    }

    /// The option as `spelling` writes it: `--wall-size` or `wall_size`.
    pub fn spelled(self, spelling: Spelling) -> String {
        match spelling {
            Spelling::Cli => format!("--{}", self.name().replace('_', "-")),
            Spelling::Python => self.name().into(),
        }
    }

    /// The option set to `value`: `--window-end keep` or `window_end='keep'`. A value in capitals
    /// (`PATH_M`) stands for one the user chooses and is not quoted.
    pub fn set(self, value: &'static str) -> Setting {
        Setting {
            opt: self,
            value: Some(value),
        }
    }

    /// A switch turned on: `--confocal` or `confocal=True`.
    pub fn on(self) -> Setting {
        Setting {
            opt: self,
            value: None,
        }
    }
}

impl fmt::Display for Opt {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.spelled(front_end()))
    }
}

/// An option with its value (or a switch turned on), as a message suggests it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Setting {
    opt: Opt,
    value: Option<&'static str>,
}

impl Setting {
    /// The setting as `spelling` writes it.
    pub fn spelled(self, spelling: Spelling) -> String {
        let name = self.opt.spelled(spelling);
        let placeholder = |v: &str| v.chars().all(|c| c.is_ascii_uppercase() || c == '_');
        match (spelling, self.value) {
            (Spelling::Cli, None) => name,
            (Spelling::Cli, Some(v)) => format!("{name} {v}"),
            (Spelling::Python, None) => format!("{name}=True"),
            (Spelling::Python, Some(v)) if placeholder(v) => format!("{name}={v}"),
            (Spelling::Python, Some(v)) => format!("{name}='{v}'"),
        }
    }
}

impl fmt::Display for Setting {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.spelled(front_end()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_front_end_spells_the_option_its_own_way() {
        use Spelling::{Cli, Python};
        assert_eq!(Opt::WallSize.spelled(Cli), "--wall-size");
        assert_eq!(Opt::WallSize.spelled(Python), "wall_size");
        assert_eq!(Opt::WindowEnd.set("keep").spelled(Cli), "--window-end keep");
        assert_eq!(
            Opt::WindowEnd.set("keep").spelled(Python),
            "window_end='keep'"
        );
        assert_eq!(Opt::Gate.set("PATH_M").spelled(Cli), "--gate PATH_M");
        assert_eq!(Opt::Gate.set("PATH_M").spelled(Python), "gate=PATH_M");
        assert_eq!(Opt::Confocal.on().spelled(Cli), "--confocal");
        assert_eq!(Opt::Confocal.on().spelled(Python), "confocal=True");
        // No front end set in a test process: the CLI's spelling.
        assert_eq!(Opt::BinWidthPs.to_string(), "--bin-width-ps");
    }
}
