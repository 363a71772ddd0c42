//! What every reconstruction method returns, and the contract each method's plan meets.

use crate::{Capture, CaptureKind, Progress, Result, Volume};

/// One reconstruction method planned for captures of one geometry ([`Capture::same_geometry`]): what
/// it builds once (FFT plans, filters, the volume) is made by its constructor, and each capture of
/// that geometry is then one [`Reconstructor::reconstruct`] call. Every method (Phasor Fields in
/// `murk-recon`, the baselines in `murk-baselines`) implements it in its own module, so the dispatcher
/// above them (`murk-methods`) holds plans of any method behind one type.
pub trait Reconstructor: Send + Sync {
    /// Reconstructs `capture`, which has the geometry the plan was made for, reporting to `progress`
    /// and stopping with an error once it is cancelled.
    fn reconstruct(&self, capture: &Capture, progress: &dyn Progress) -> Result<Reconstruction>;
}

/// A reconstructed volume by any method: `intensity[volume.index(ix, iy, iz)]`, C order [nx, ny, nz],
/// with the rows that say how it was made and the warnings met on the way.
#[derive(Clone, Debug)]
pub struct Reconstruction {
    pub volume: Volume,
    pub intensity: Vec<f32>,
    /// The unit surface normal per voxel (indexed as `intensity`; n_z < 0 faces the wall), zero
    /// where the intensity is: given by the methods that recover surface orientation (dlct), `None`
    /// by the others. Writers store it beside the volume whichever method gave it.
    pub normals: Option<Vec<[f32; 3]>>,
    /// How it was made, as (key, value) rows for summaries and file attributes.
    pub rows: Vec<(String, String)>,
    pub warnings: Vec<String>,
}

impl Reconstruction {
    /// A reconstruction with its method's description as the first row.
    pub fn new(volume: Volume, intensity: Vec<f32>, method: &str) -> Reconstruction {
        Reconstruction {
            volume,
            intensity,
            normals: None,
            rows: vec![("method".into(), method.into())],
            warnings: Vec::new(),
        }
    }

    /// Appends a (key, value) row.
    pub fn row(mut self, key: &str, value: impl ToString) -> Reconstruction {
        self.rows.push((key.into(), value.to_string()));
        self
    }

    /// Zeroes the normals of the voxels whose intensity is zero (after a step cleared them), so that
    /// a normal stands only where there is a surface.
    pub fn clear_dark_normals(&mut self) {
        if let Some(normals) = &mut self.normals {
            for (n, &v) in normals.iter_mut().zip(&self.intensity) {
                if v == 0.0 {
                    *n = [0.0; 3];
                }
            }
        }
    }

    /// (ix, iy, iz) of the largest value (the last one on ties; NaN sorts above everything).
    pub fn argmax(&self) -> [usize; 3] {
        let i = self
            .intensity
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map_or(0, |(i, _)| i);
        let (ix, iy, iz) = self.volume.unravel(i);
        [ix, iy, iz]
    }

    /// Position and value of the largest voxel.
    pub fn peak(&self) -> ([f64; 3], f32) {
        let [ix, iy, iz] = self.argmax();
        let v = self
            .intensity
            .get(self.volume.index(ix, iy, iz))
            .copied()
            .unwrap_or(0.0);
        (self.volume.centre(ix, iy, iz).to_array(), v)
    }

    /// The capture, the method's rows, the volume, the peak and the time as (key, value) rows: what
    /// `murk reconstruct` prints and records next to the volume.
    pub fn summary(&self, capture: &str, kind: CaptureKind, secs: f64) -> Vec<(String, String)> {
        let (p, val) = self.peak();
        let v = &self.volume;
        let mut t = vec![
            ("capture".into(), capture.to_string()),
            ("capture kind".into(), kind.to_string()),
        ];
        t.extend(self.rows.iter().cloned());
        t.extend([
            (
                "volume".into(),
                format!(
                    "x {:.4}:{:.4}:{}, y {:.4}:{:.4}:{}, z {:.4}:{:.4}:{}",
                    v.x.start, v.x.end, v.x.n, v.y.start, v.y.end, v.y.n, v.z.start, v.z.end, v.z.n
                ),
            ),
            (
                "peak".into(),
                format!(
                    "{val:.4e} at x {:+.4}, y {:+.4}, z {:.4} m",
                    p[0], p[1], p[2]
                ),
            ),
            ("seconds".into(), format!("{secs:.3}")),
            ("murk_version".into(), env!("CARGO_PKG_VERSION").into()),
        ]);
        t
    }
}
