use crate::{DVec3, Error, Result};

/// `n` sample positions from `start` to `end` inclusive (numpy's linspace).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Axis {
    pub start: f64,
    pub end: f64,
    pub n: usize,
}

impl Axis {
    pub fn new(start: f64, end: f64, n: usize) -> Self {
        Axis { start, end, n }
    }
    pub fn at(&self, i: usize) -> f64 {
        if self.n <= 1 {
            self.start
        } else {
            self.start + (self.end - self.start) * i as f64 / (self.n - 1) as f64
        }
    }
    /// Spacing between samples (0 for a single sample).
    pub fn step(&self) -> f64 {
        if self.n <= 1 {
            0.0
        } else {
            (self.end - self.start) / (self.n - 1) as f64
        }
    }
    pub fn values(&self) -> Vec<f64> {
        (0..self.n).map(|i| self.at(i)).collect()
    }
}

/// A box of voxel centres in world coordinates, x and y along the wall, z the depth (z > 0 hidden).
/// Voxel (ix, iy, iz) is stored at index (ix·ny + iy)·nz + iz (C order, shape [nx, ny, nz]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Volume {
    pub x: Axis,
    pub y: Axis,
    pub z: Axis,
}

impl Volume {
    pub fn len(&self) -> usize {
        self.x.n * self.y.n * self.z.n
    }
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
    pub fn shape(&self) -> [usize; 3] {
        [self.x.n, self.y.n, self.z.n]
    }
    pub fn index(&self, ix: usize, iy: usize, iz: usize) -> usize {
        (ix * self.y.n + iy) * self.z.n + iz
    }
    /// The (ix, iy, iz) of C-order index `i` (the inverse of [`Volume::index`]).
    pub fn unravel(&self, i: usize) -> (usize, usize, usize) {
        let (ny, nz) = (self.y.n, self.z.n);
        (i / (ny * nz), (i / nz) % ny, i % nz)
    }

    pub fn centre(&self, ix: usize, iy: usize, iz: usize) -> DVec3 {
        DVec3::new(self.x.at(ix), self.y.at(iy), self.z.at(iz))
    }

    /// Parses `x0:x1:nx,y0:y1:ny,z0:z1:nz` (metres, inclusive ends with start ≤ end, counts ≥ 1).
    /// The message names the volume, not a flag: the CLI and Python both call this.
    pub fn parse(spec: &str) -> Result<Volume> {
        let bad = |why: &str| {
            Error::param(format!(
                "volume '{spec}': {why} (expected x0:x1:nx,y0:y1:ny,z0:z1:nz)"
            ))
        };
        let parts: Vec<&str> = spec.split(',').collect();
        if parts.len() != 3 {
            return Err(bad("need three comma-separated axes"));
        }
        let mut axes = [Axis::new(0.0, 0.0, 1); 3];
        for (axis, part) in axes.iter_mut().zip(&parts) {
            let f: Vec<&str> = part.split(':').collect();
            if f.len() != 3 {
                return Err(bad(&format!("axis '{part}' is not start:end:count")));
            }
            let start: f64 = f[0]
                .trim()
                .parse()
                .map_err(|_| bad(&format!("'{}' is not a number", f[0])))?;
            let end: f64 = f[1]
                .trim()
                .parse()
                .map_err(|_| bad(&format!("'{}' is not a number", f[1])))?;
            let n: usize = f[2]
                .trim()
                .parse()
                .map_err(|_| bad(&format!("'{}' is not a voxel count", f[2])))?;
            if !start.is_finite() || !end.is_finite() {
                return Err(bad("bounds must be finite"));
            }
            if n == 0 {
                return Err(bad("voxel counts must be at least 1"));
            }
            // Pictures and depths read an axis from its start to its end: a reversed one would
            // draw the scene mirrored without a word.
            if start > end {
                return Err(bad(&format!(
                    "axis '{part}' runs from {start} down to {end}; give the smaller bound first"
                )));
            }
            *axis = Axis::new(start, end, n);
        }
        let v = Volume {
            x: axes[0],
            y: axes[1],
            z: axes[2],
        };
        v.validate()?;
        Ok(v)
    }

    /// Rejects volumes murk cannot reconstruct into: voxels on or behind the wall, absurd sizes.
    pub fn validate(&self) -> Result<()> {
        let limits = crate::Limits::get();
        for (name, a) in [("x", &self.x), ("y", &self.y), ("z", &self.z)] {
            limits.length(&format!("the volume's {name} start"), a.start)?;
            limits.length(&format!("the volume's {name} end"), a.end)?;
            // Voxels that all but coincide (1e-12 m apart) repeat one value: a mistyped unit, not a volume.
            let span = (a.end - a.start).abs();
            if a.n > 1 && span < limits.min_bin_width_m {
                return Err(Error::param(format!(
                    "the volume's {name} axis spans {} m over {} voxels; murk accepts axes of several voxels spanning at least {} m",
                    crate::short(span),
                    a.n,
                    crate::short(limits.min_bin_width_m)
                )));
            }
        }
        let zmin = self.z.start.min(self.z.end);
        if zmin <= 0.0 {
            return Err(Error::param(format!(
                "the volume reaches z = {zmin} m, on or behind the relay wall (z = 0); depths must be > 0"
            )));
        }
        // A reconstruction holds the field as complex f64 per voxel.
        limits.elements(
            "the volume",
            &[self.x.n, self.y.n, self.z.n],
            std::mem::size_of::<[f64; 2]>(),
        )?;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parse_linspace() {
        let v = Volume::parse("-1:1:5,0:0:1,0.5:1.5:3").unwrap();
        assert_eq!(v.x.values(), vec![-1.0, -0.5, 0.0, 0.5, 1.0]);
        assert_eq!(v.y.values(), vec![0.0]);
        assert_eq!(v.z.at(2), 1.5);
        assert_eq!(v.shape(), [5, 1, 3]);
    }

    #[test]
    fn parse_rejects_nonsense() {
        for s in [
            "",
            "1:2:3",
            "a:1:2,0:1:2,1:2:2",
            "0:1:0,0:1:2,1:2:2",
            "0:1:2,0:1:2,-1:2:2",
            "0:1:2,0:1:2,0:1:2",
            "0:1e-12:4,0:1:2,1:2:2",
            "0:1:2,0:1:2,0.5:0.5:3",
            "1:0:10,0:1:2,1:2:2",
            "0:1:2,0:1:2,2:1:2",
        ] {
            assert!(Volume::parse(s).is_err(), "{s}");
        }
        let e = Volume::parse("0:1:2,0:1:2,-1:2:2").unwrap_err().to_string();
        assert!(e.contains("behind the relay wall"), "{e}");
        let e = Volume::parse("1:0:10,0:1:2,1:2:2").unwrap_err().to_string();
        assert!(
            e.contains("axis '1:0:10' runs from 1 down to 0") && !e.contains("--volume"),
            "{e}"
        );
    }
}
