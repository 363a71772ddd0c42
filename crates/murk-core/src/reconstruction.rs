//! What every reconstruction method returns.

use crate::Volume;

/// A reconstructed volume by any method: `intensity[volume.index(ix, iy, iz)]`, C order [nx, ny, nz],
/// with the rows that say how it was made and the warnings met on the way.
#[derive(Clone, Debug)]
pub struct Reconstruction {
    pub volume: Volume,
    pub intensity: Vec<f32>,
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
            rows: vec![("method".into(), method.into())],
            warnings: Vec::new(),
        }
    }

    /// Appends a (key, value) row.
    pub fn row(mut self, key: &str, value: impl ToString) -> Reconstruction {
        self.rows.push((key.into(), value.to_string()));
        self
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

    /// Maximum along depth, [nx][ny] row-major.
    pub fn max_projection(&self) -> Vec<f32> {
        self.intensity
            .chunks(self.volume.z.n)
            .map(|c| c.iter().copied().fold(f32::MIN, f32::max))
            .collect()
    }
}
