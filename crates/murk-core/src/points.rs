use crate::{DVec3, Error, Result};

/// How the points of a [`PointSet`] are arranged.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointLayout {
    /// `nx × ny` points stored x-major: index = ix·ny + iy (y-tal's `X_Y_3`, C order).
    Grid { nx: usize, ny: usize },
    /// An unstructured list (y-tal's `N_3`).
    List,
}

/// Points on the relay surface, with their surface normals.
#[derive(Clone, Debug, PartialEq)]
pub struct PointSet {
    pub points: Vec<DVec3>,
    pub normals: Vec<DVec3>,
    pub layout: PointLayout,
}

/// A planar, regularly spaced grid: point(ix, iy) = origin + ix·step_x + iy·step_y.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RegularGrid {
    pub origin: DVec3,
    pub step_x: DVec3,
    pub step_y: DVec3,
    pub nx: usize,
    pub ny: usize,
}

impl RegularGrid {
    pub fn point(&self, ix: usize, iy: usize) -> DVec3 {
        self.origin + self.step_x * ix as f64 + self.step_y * iy as f64
    }
    /// Unit normal of the grid plane (step_x × step_y), oriented towards +z when the plane is not vertical.
    pub fn normal(&self) -> DVec3 {
        let n = self.step_x.cross(self.step_y).normalize_or_zero();
        if n.z < 0.0 {
            -n
        } else {
            n
        }
    }
}

impl PointSet {
    /// One point with normal +z.
    pub fn single(p: DVec3) -> Self {
        PointSet {
            points: vec![p],
            normals: vec![DVec3::Z],
            layout: PointLayout::Grid { nx: 1, ny: 1 },
        }
    }

    /// `nx × ny` pixel-centre grid over `[cx − wx/2, cx + wx/2] × [cy − wy/2, cy + wy/2]` at z = 0, normals +z.
    /// This is the layout `tal render` produces for a wall of that size.
    pub fn wall_grid(centre: DVec3, size_x_m: f64, size_y_m: f64, nx: usize, ny: usize) -> Self {
        let dx = size_x_m / nx as f64;
        let dy = size_y_m / ny as f64;
        let mut points = Vec::with_capacity(nx * ny);
        for ix in 0..nx {
            for iy in 0..ny {
                points.push(DVec3::new(
                    centre.x - size_x_m / 2.0 + (ix as f64 + 0.5) * dx,
                    centre.y - size_y_m / 2.0 + (iy as f64 + 0.5) * dy,
                    centre.z,
                ));
            }
        }
        PointSet {
            normals: vec![DVec3::Z; points.len()],
            points,
            layout: PointLayout::Grid { nx, ny },
        }
    }

    pub fn len(&self) -> usize {
        self.points.len()
    }

    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }

    /// The grid shape as (nx, ny); a list of n points reports (n, 1).
    pub fn shape(&self) -> (usize, usize) {
        match self.layout {
            PointLayout::Grid { nx, ny } => (nx, ny),
            PointLayout::List => (self.points.len(), 1),
        }
    }

    /// Checks sizes and finiteness; `what` names the set in the message.
    pub fn validate(&self, what: &str) -> Result<()> {
        if self.points.is_empty() {
            return Err(Error::param(format!("{what}: no points")));
        }
        if self.normals.len() != self.points.len() {
            return Err(Error::param(format!(
                "{what}: {} points but {} normals",
                self.points.len(),
                self.normals.len()
            )));
        }
        if let PointLayout::Grid { nx, ny } = self.layout {
            if nx * ny != self.points.len() {
                return Err(Error::param(format!(
                    "{what}: grid {nx}×{ny} but {} points",
                    self.points.len()
                )));
            }
        }
        if let Some(i) = self
            .points
            .iter()
            .chain(&self.normals)
            .position(|p| !p.is_finite())
        {
            let n = self.points.len();
            let which = if i < n {
                format!("point {i}")
            } else {
                format!("the normal of point {}", i - n)
            };
            return Err(Error::param(format!(
                "{what}: non-finite coordinate in {which}"
            )));
        }
        let limits = crate::Limits::get();
        let far = self
            .points
            .iter()
            .copied()
            .enumerate()
            .max_by(|a, b| a.1.abs().max_element().total_cmp(&b.1.abs().max_element()));
        if let Some((i, p)) = far {
            limits.length(
                &format!("{what}: entry {i}'s largest |coordinate|"),
                p.abs().max_element(),
            )?;
        }
        // A grid whose points all but coincide (a scan side of 1e-300 m) has no aperture to image with.
        if matches!(self.layout, PointLayout::Grid { .. }) && self.points.len() > 1 {
            let (lo, hi) = self
                .points
                .iter()
                .fold((self.points[0], self.points[0]), |(lo, hi), p| {
                    (lo.min(*p), hi.max(*p))
                });
            let span = (hi - lo).max_element();
            if span < limits.min_bin_width_m {
                return Err(Error::Limits(format!(
                    "{what}: the grid's points span {} m; murk accepts grids spanning at least {} m",
                    crate::short(span),
                    crate::short(limits.min_bin_width_m)
                )));
            }
        }
        Ok(())
    }

    /// The regular planar grid these points form, if they form one (relative tolerance 1e-4 of the step).
    /// Grids of one row or column are accepted with a step perpendicular to it; a single point is not a grid.
    pub fn regular_grid(&self) -> Option<RegularGrid> {
        let PointLayout::Grid { nx, ny } = self.layout else {
            return None;
        };
        if nx < 2 || ny < 2 {
            return None;
        }
        let p = |ix: usize, iy: usize| self.points[ix * ny + iy];
        let origin = p(0, 0);
        let step_x = (p(nx - 1, 0) - origin) / (nx - 1) as f64;
        let step_y = (p(0, ny - 1) - origin) / (ny - 1) as f64;
        let tol = 1e-4 * step_x.length().min(step_y.length());
        if tol == 0.0 || step_x.normalize().dot(step_y.normalize()).abs() > 1e-6 {
            return None;
        }
        let g = RegularGrid {
            origin,
            step_x,
            step_y,
            nx,
            ny,
        };
        for ix in 0..nx {
            for iy in 0..ny {
                if (p(ix, iy) - g.point(ix, iy)).length() > tol {
                    return None;
                }
            }
        }
        Some(g)
    }

    /// Mean spacing between neighbouring grid points (Δc of the paper); `None` for lists and single points.
    pub fn spacing_m(&self) -> Option<f64> {
        self.regular_grid()
            .map(|g| 0.5 * (g.step_x.length() + g.step_y.length()))
    }

    /// Centroid of the points (the paper's ⟨S⟩).
    pub fn centroid(&self) -> DVec3 {
        self.points.iter().copied().sum::<DVec3>() / self.points.len().max(1) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wall_grid_is_regular_pixel_centres() {
        let w = PointSet::wall_grid(DVec3::ZERO, 1.0, 1.0, 4, 4);
        assert_eq!(w.points[0], DVec3::new(-0.375, -0.375, 0.0));
        // x-major: the second point moves along y.
        assert_eq!(w.points[1], DVec3::new(-0.375, -0.125, 0.0));
        let g = w.regular_grid().expect("regular");
        assert!((g.step_x - DVec3::new(0.25, 0.0, 0.0)).length() < 1e-12);
        assert_eq!(w.spacing_m(), Some(0.25));
    }

    #[test]
    fn jittered_grid_is_not_regular() {
        let mut w = PointSet::wall_grid(DVec3::ZERO, 1.0, 1.0, 4, 4);
        w.points[5].x += 0.01;
        assert!(w.regular_grid().is_none());
        assert!(PointSet::single(DVec3::ZERO).regular_grid().is_none());
    }
}
