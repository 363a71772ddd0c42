//! A heterogeneous medium's density cells, as a capture rendered through one carries them: what the
//! compensation and the medium's estimate read instead of a density the user gives by hand.

/// The most cells a density grid may have (256³: 64 MiB of f32).
pub const MAX_DENSITY_CELLS: u64 = 1 << 24;

/// nx × ny × nz cells of constant density filling the medium's box, in C order: cell (i, j, k) at
/// (i·ny + j)·nz + k. Made only by [`DensityCells::new`], so every value is finite and ≥ 0 and one
/// is above 0.
#[derive(Clone, Debug, PartialEq)]
pub struct DensityCells {
    dims: [usize; 3],
    values: Vec<f32>,
}

impl DensityCells {
    /// The cells of `shape` (nx, ny, nz). The message of an error says what is wrong, for the
    /// caller to prefix with where the cells came from: a rank other than 3, no cells, more than
    /// [`MAX_DENSITY_CELLS`], a shape that does not hold the values, a density that is negative or
    /// not finite, or no density above zero.
    pub fn new(shape: &[usize], values: Vec<f32>) -> std::result::Result<DensityCells, String> {
        let &[nx, ny, nz] = shape else {
            return Err(format!(
                "a density grid has 3 dimensions (nx, ny, nz), this one has shape {shape:?}"
            ));
        };
        let cells = (nx as u64)
            .checked_mul(ny as u64)
            .and_then(|n| n.checked_mul(nz as u64));
        match cells {
            Some(0) => return Err(format!("the density grid {shape:?} has no cells")),
            Some(n) if n <= MAX_DENSITY_CELLS && n as usize == values.len() => {}
            Some(n) if n <= MAX_DENSITY_CELLS => {
                return Err(format!(
                    "the density grid's shape {shape:?} holds {n} cells but {} values are stored",
                    values.len()
                ))
            }
            _ => {
                return Err(format!(
                    "the density grid {shape:?} has more than {MAX_DENSITY_CELLS} cells (256³)"
                ))
            }
        }
        if let Some(at) = values.iter().position(|v| !(v.is_finite() && *v >= 0.0)) {
            let (i, j, k) = (at / (ny * nz), at / nz % ny, at % nz);
            return Err(format!(
                "density[{i}, {j}, {k}] = {}: densities must be finite and ≥ 0",
                values[at]
            ));
        }
        if !values.iter().any(|&v| v > 0.0) {
            return Err(
                "every density is 0: the medium would be empty (leave [medium] out)".into(),
            );
        }
        Ok(DensityCells {
            dims: [nx, ny, nz],
            values,
        })
    }

    /// Cell counts along x, y, z.
    pub fn dims(&self) -> [usize; 3] {
        self.dims
    }

    /// The densities in C order.
    pub fn values(&self) -> &[f32] {
        &self.values
    }

    /// The largest density.
    pub fn max(&self) -> f32 {
        self.values.iter().fold(0.0, |a, &v| a.max(v))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bad_cells_are_named() {
        let err = |shape: &[usize], v: Vec<f32>| DensityCells::new(shape, v).unwrap_err();
        assert!(err(&[2, 2], vec![1.0; 4]).contains("3 dimensions"));
        assert!(err(&[2, 0, 2], vec![]).contains("has no cells"));
        assert!(err(&[2, 2, 2], vec![1.0; 7]).contains("holds 8 cells but 7 values"));
        assert!(err(&[1 << 9, 1 << 9, 1 << 9], vec![]).contains("more than 16777216 cells"));
        assert!(err(&[usize::MAX, 2, 2], vec![]).contains("more than"));
        let mut v = vec![1.0; 8];
        v[5] = f32::NAN;
        assert!(err(&[2, 2, 2], v).contains("density[1, 0, 1] = NaN"));
        assert!(err(&[1, 1, 2], vec![0.0, -1.0]).contains("density[0, 0, 1] = -1"));
        assert!(err(&[1, 1, 2], vec![0.0; 2]).contains("every density is 0"));
        let ok = DensityCells::new(&[1, 2, 1], vec![0.0, 2.5]).unwrap();
        assert_eq!((ok.dims(), ok.max()), ([1, 2, 1], 2.5));
    }
}
