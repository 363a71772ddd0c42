//! Ground truth of a hidden scene as seen from the relay: what the renderer knows and a reconstruction
//! should find.

/// Per point of a lattice on the relay plane (x-major, `[nx, ny]` in C order like the wall grid), the
/// first hidden surface met along the relay normal (+z) and the object it belongs to.
#[derive(Clone, Debug, PartialEq)]
pub struct GroundTruth {
    /// Lattice coordinates on the relay (m).
    pub x_m: Vec<f64>,
    pub y_m: Vec<f64>,
    /// Depth z of the first surface (m); NaN where the normal ray meets nothing.
    pub depth_m: Vec<f32>,
    /// Index of that surface's object in the scene's `[[object]]` list; −1 where none.
    pub object: Vec<i32>,
    /// One name per object of the scene (its `name`, or `object[i] (shape)`).
    pub object_names: Vec<String>,
    /// Axis-aligned bounds of the hidden geometry (m).
    pub bounds_min_m: [f64; 3],
    pub bounds_max_m: [f64; 3],
}

impl GroundTruth {
    pub fn shape(&self) -> [usize; 2] {
        [self.x_m.len(), self.y_m.len()]
    }
}
