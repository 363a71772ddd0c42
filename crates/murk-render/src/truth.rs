//! Ground truth of a scene: the first hidden surface along the relay normal from each point of a
//! lattice on the relay, exact at the points (a ray cast against the same primitives the renderer hits).

use crate::scene::{ObjectDef, Scene};
use murk_core::{DVec3, GroundTruth, PointLayout};

impl ObjectDef {
    /// The object's label: its `name`, or `object[i] (shape)`.
    pub fn label(&self, i: usize) -> String {
        let (name, shape) = match self {
            ObjectDef::Quad { name, .. } => (name, "quad"),
            ObjectDef::Box { name, .. } => (name, "box"),
            ObjectDef::ZLetter { name, .. } => (name, "z-letter"),
            ObjectDef::Mesh { name, .. } => (name, "mesh"),
        };
        name.clone()
            .unwrap_or_else(|| format!("object[{i}] ({shape})"))
    }
}

impl Scene {
    /// Ground truth on the lattice `x_m × y_m` of the relay plane.
    pub fn ground_truth_on(&self, x_m: &[f64], y_m: &[f64]) -> GroundTruth {
        let mut depth_m = Vec::with_capacity(x_m.len() * y_m.len());
        let mut object = Vec::with_capacity(depth_m.capacity());
        for &x in x_m {
            for &y in y_m {
                match self.geometry.first_object(DVec3::new(x, y, 0.0), DVec3::Z) {
                    Some((k, t)) => {
                        depth_m.push(t as f32);
                        object.push(k as i32);
                    }
                    None => {
                        depth_m.push(f32::NAN);
                        object.push(-1);
                    }
                }
            }
        }
        let b = self.geometry.bounds();
        GroundTruth {
            x_m: x_m.to_vec(),
            y_m: y_m.to_vec(),
            depth_m,
            object,
            object_names: self.object_names.clone(),
            bounds_min_m: b.min.to_array(),
            bounds_max_m: b.max.to_array(),
        }
    }

    /// Ground truth at the capture's wall grid (the gridded side with more points).
    pub fn ground_truth(&self) -> GroundTruth {
        let c = &self.capture;
        let side = if c.illum.len() >= c.sensor.len() {
            &c.illum
        } else {
            &c.sensor
        };
        let (nx, ny) = match side.layout {
            PointLayout::Grid { nx, ny } => (nx, ny),
            PointLayout::List => (side.len(), 1),
        };
        let x_m: Vec<f64> = (0..nx).map(|i| side.points[i * ny].x).collect();
        let y_m: Vec<f64> = (0..ny).map(|j| side.points[j].y).collect();
        self.ground_truth_on(&x_m, &y_m)
    }
}
