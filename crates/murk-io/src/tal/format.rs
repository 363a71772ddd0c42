//! The layouts a y-tal file names: H's (`H_format`) and the point sets' (`*_grid_format`), and
//! which H layout murk writes for a capture.

use murk_core::{Capture, Pairing, PointLayout, PointSet};

/// H's layout, time axis first (y-tal's `HFormat`; murk reads and writes its time-domain members).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum HFormat {
    /// (T, Sx, Sy): one laser point, or a laser grid paired with the sensor grid.
    SxSy,
    /// (T, Lx, Ly, Sx, Sy): every laser grid point with every sensor grid point.
    LxLySxSy,
    /// (T, N): as `SxSy` for point lists.
    Si,
    /// (T, Nl, Ns): as `LxLySxSy` for point lists.
    LiSi,
}

impl HFormat {
    const ALL: [HFormat; 4] = [HFormat::SxSy, HFormat::LxLySxSy, HFormat::Si, HFormat::LiSi];

    /// y-tal's member name.
    pub(crate) fn name(self) -> &'static str {
        match self {
            HFormat::SxSy => "T_Sx_Sy",
            HFormat::LxLySxSy => "T_Lx_Ly_Sx_Sy",
            HFormat::Si => "T_Si",
            HFormat::LiSi => "T_Li_Si",
        }
    }

    /// y-tal's enum value.
    pub(crate) fn code(self) -> i32 {
        match self {
            HFormat::SxSy => 1,
            HFormat::LxLySxSy => 2,
            HFormat::Si => 3,
            HFormat::LiSi => 4,
        }
    }

    /// The layout a file's `H_format` holds, by member name or by value; `None` for y-tal's others
    /// (UNKNOWN, the frequency-domain ones) and for what y-tal could not name.
    pub(crate) fn read(text: &str) -> Option<HFormat> {
        HFormat::ALL
            .into_iter()
            .find(|f| f.name() == text || f.code().to_string() == text)
    }

    /// The enum's members as a file declares them.
    pub(crate) fn members() -> Vec<(&'static str, i32)> {
        let mut m = vec![("UNKNOWN", 0)];
        m.extend(HFormat::ALL.map(|f| (f.name(), f.code())));
        m
    }
}

/// The point sets' layouts (`*_grid_format`): y-tal's member names and values.
pub(crate) const GRID_FORMATS: [(&str, i32); 3] = [("UNKNOWN", 0), ("N_3", 1), ("X_Y_3", 2)];

/// How a capture is written: H's layout and the point sets'.
pub(crate) struct WriteLayout {
    pub h_format: HFormat,
    /// H's non-time dimensions.
    pub h_dims: Vec<usize>,
    /// Write both point sets as `N_3` lists regardless of their layout.
    pub lists: bool,
}

/// A point set's non-time dimensions in H: (X, Y) for a grid, (N) for a list.
pub(crate) fn dims(p: &PointSet) -> Vec<usize> {
    match p.layout {
        PointLayout::Grid { nx, ny } => vec![nx, ny],
        PointLayout::List => vec![p.len()],
    }
}

impl WriteLayout {
    /// The layout murk writes `cap` in (the module docs list the choices).
    pub(crate) fn of(cap: &Capture) -> WriteLayout {
        let (il, sl) = (cap.illum.layout, cap.sensor.layout);
        let sensor_grid = matches!(sl, PointLayout::Grid { .. });
        let (h_format, h_dims, lists) = match cap.pairing {
            Pairing::Paired if sensor_grid && il == sl => (HFormat::SxSy, dims(&cap.sensor), false),
            Pairing::Paired => (HFormat::Si, vec![cap.sensor.len()], true),
            Pairing::Product if cap.illum.len() == 1 => {
                let f = if sensor_grid {
                    HFormat::SxSy
                } else {
                    HFormat::Si
                };
                (f, dims(&cap.sensor), false)
            }
            Pairing::Product if sensor_grid && matches!(il, PointLayout::Grid { .. }) => (
                HFormat::LxLySxSy,
                [dims(&cap.illum), dims(&cap.sensor)].concat(),
                false,
            ),
            Pairing::Product => (
                HFormat::LiSi,
                vec![cap.illum.len(), cap.sensor.len()],
                false,
            ),
        };
        WriteLayout {
            h_format,
            h_dims,
            lists,
        }
    }
}
