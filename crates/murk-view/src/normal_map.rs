//! The front view's normal map: the surface normal of the brightest voxel behind each pixel, for the
//! methods that give normals (a [`murk_core::Reconstruction`]'s `normals`).

use crate::pictures::{write_pixels, Views, SURFACE_LEVEL};
use murk_core::Result;
use std::path::{Path, PathBuf};

/// The normal map's file in the pictures' folder.
pub const FILE: &str = "normals.png";

/// The colour of unit normal `n`: red n_x, green n_y, blue −n_z (towards the wall), each −1..1
/// mapped to 0..255, so a surface facing the wall straight on is (128, 128, 255).
pub fn normal_colour(n: [f32; 3]) -> [u8; 3] {
    let c = |v: f32| ((v.clamp(-1.0, 1.0) + 1.0) * 127.5).round() as u8;
    [c(n[0]), c(n[1]), c(-n[2])]
}

/// The normal behind each front pixel of `v` (of the volume `normals` are indexed by), `None` where
/// the pixel is dimmer than the depth map's threshold or has no normal.
pub fn front_normals(v: &Views, normals: &[[f32; 3]]) -> Vec<Option<[f32; 3]>> {
    let max = v.front.values.iter().cloned().fold(0.0, f32::max);
    v.front_voxels
        .iter()
        .zip(&v.front.values)
        .map(|(&i, &f)| {
            let n = normals[i];
            (f >= SURFACE_LEVEL * max && f > 0.0 && n != [0.0; 3]).then_some(n)
        })
        .collect()
}

/// Writes `dir`/normals.png; returns its path with its caption.
pub(crate) fn write(dir: &Path, v: &Views, normals: &[[f32; 3]]) -> Result<(PathBuf, String)> {
    let front = front_normals(v, normals);
    let p = dir.join(FILE);
    let key = "colour: red n_x, green n_y, blue −n_z (towards the wall), −1..1 as dark..bright; black: no surface";
    write_pixels(&p, &v.front, key.into(), |i| {
        front[i].map_or([0, 0, 0], normal_colour)
    })?;
    Ok((
        p,
        format!(
            "normals of the brightest voxel, seen from the wall ({}; {key})",
            v.front.extents
        ),
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use murk_core::Volume;

    /// A surface facing the wall straight on is the map's blue; a dim column and a voxel without a
    /// normal are black; each pixel takes the normal of its brightest voxel.
    #[test]
    fn each_pixel_takes_its_brightest_voxels_normal() {
        let vol = Volume::parse("-1:1:3,0:0:1,1:2:2").unwrap();
        let mut intensity = vec![0f32; vol.len()];
        let mut normals = vec![[0f32; 3]; vol.len()];
        let tilted = [0.6, 0.0, -0.8];
        intensity[vol.index(2, 0, 1)] = 1.0; // x = +1: the left column
        normals[vol.index(2, 0, 1)] = tilted;
        intensity[vol.index(2, 0, 0)] = 0.5;
        normals[vol.index(2, 0, 0)] = [0.0, 0.0, -1.0];
        intensity[vol.index(1, 0, 0)] = 0.1; // below 20 % of the maximum
        normals[vol.index(1, 0, 0)] = [0.0, 0.0, -1.0];
        intensity[vol.index(0, 0, 1)] = 0.9; // bright, no normal
        let v = crate::views(&vol, &intensity);
        assert_eq!(front_normals(&v, &normals), [Some(tilted), None, None]);
        assert_eq!(normal_colour([0.0, 0.0, -1.0]), [128, 128, 255]);
        assert_eq!(normal_colour(tilted), [204, 128, 230]);
    }
}
