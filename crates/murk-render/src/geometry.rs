//! Hidden-scene geometry: rectangles and triangles in a bounding volume hierarchy. Surfaces are two-sided
//! Lambertian reflectors.

use murk_core::DVec3;

/// Rays do not re-hit a surface closer than this (metres).
pub const EPS: f64 = 1e-7;

/// A closed set of primitive kinds, dispatched statically (no trait objects in the inner loop).
#[derive(Clone, Debug)]
pub enum Shape {
    /// `p0 + u·e1 + v·e2`, u, v ∈ [0, 1], with e1 ⟂ e2; built by `Shape::rect`, which precomputes the
    /// rest for the intersection test (the renderer's hottest function).
    Rect {
        p0: DVec3,
        e1: DVec3,
        e2: DVec3,
        /// Unit normal e1 × e2 / |e1 × e2|.
        n: DVec3,
        /// e1/|e1|² and e2/|e2|²: a point's (u, v) by dot products.
        e1s: DVec3,
        e2s: DVec3,
    },
    Triangle {
        p0: DVec3,
        e1: DVec3,
        e2: DVec3,
    },
}

impl Shape {
    pub fn rect(p0: DVec3, e1: DVec3, e2: DVec3) -> Self {
        Shape::Rect {
            p0,
            e1,
            e2,
            n: e1.cross(e2).normalize(),
            e1s: e1 / e1.length_squared(),
            e2s: e2 / e2.length_squared(),
        }
    }

    pub fn area(&self) -> f64 {
        match self {
            Shape::Rect { e1, e2, .. } => e1.cross(*e2).length(),
            Shape::Triangle { e1, e2, .. } => 0.5 * e1.cross(*e2).length(),
        }
    }

    /// Unit geometric normal (e1 × e2); surfaces are two-sided, so its sign only matters for meshes' users.
    pub fn normal(&self) -> DVec3 {
        match self {
            Shape::Rect { n, .. } => *n,
            Shape::Triangle { e1, e2, .. } => e1.cross(*e2).normalize(),
        }
    }

    /// Ray parameter of the hit in (`EPS`, `t_max`), if any.
    pub fn intersect(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<f64> {
        match self {
            Shape::Rect {
                p0, n, e1s, e2s, ..
            } => {
                let denom = n.dot(d);
                if denom.abs() < 1e-300 {
                    return None;
                }
                let t = n.dot(*p0 - o) / denom;
                if !(t > EPS && t < t_max) {
                    return None;
                }
                let q = o + d * t - *p0;
                let u = q.dot(*e1s);
                let v = q.dot(*e2s);
                ((0.0..=1.0).contains(&u) && (0.0..=1.0).contains(&v)).then_some(t)
            }
            Shape::Triangle { p0, e1, e2 } => {
                // Möller–Trumbore.
                let p = d.cross(*e2);
                let det = e1.dot(p);
                if det.abs() < 1e-300 {
                    return None;
                }
                let inv = 1.0 / det;
                let s = o - *p0;
                let u = s.dot(p) * inv;
                if !(0.0..=1.0).contains(&u) {
                    return None;
                }
                let q = s.cross(*e1);
                let v = d.dot(q) * inv;
                if v < 0.0 || u + v > 1.0 {
                    return None;
                }
                let t = e2.dot(q) * inv;
                (t > EPS && t < t_max).then_some(t)
            }
        }
    }

    /// A uniformly distributed point for `(u1, u2)` uniform in [0, 1)².
    pub fn sample(&self, u1: f64, u2: f64) -> DVec3 {
        match self {
            Shape::Rect { p0, e1, e2, .. } => *p0 + *e1 * u1 + *e2 * u2,
            Shape::Triangle { p0, e1, e2 } => {
                let su = u1.sqrt();
                *p0 + *e1 * (1.0 - su) + *e2 * (u2 * su)
            }
        }
    }

    pub fn bounds(&self) -> Aabb {
        let (p0, e1, e2, far) = match self {
            Shape::Rect { p0, e1, e2, .. } => (*p0, *e1, *e2, *p0 + *e1 + *e2),
            Shape::Triangle { p0, e1, e2 } => (*p0, *e1, *e2, *p0),
        };
        Aabb::empty().grow(p0).grow(p0 + e1).grow(p0 + e2).grow(far)
    }
}

/// Axis-aligned box.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Aabb {
    pub min: DVec3,
    pub max: DVec3,
}

impl Aabb {
    pub fn empty() -> Self {
        Aabb {
            min: DVec3::INFINITY,
            max: DVec3::NEG_INFINITY,
        }
    }
    pub fn grow(self, p: DVec3) -> Self {
        Aabb {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }
    pub fn union(self, o: Aabb) -> Self {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
    /// Whether the two boxes share a point.
    pub fn overlaps(&self, o: &Aabb) -> bool {
        self.min.cmple(o.max).all() && o.min.cmple(self.max).all()
    }
    /// The part `[t0, t1]` of the ray inside the box, clipped to `[0, t_max]`; `None` if empty.
    pub fn clip(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<(f64, f64)> {
        self.clip_inv(o, d.recip(), t_max)
    }
    /// `clip` with the ray direction's reciprocal precomputed.
    fn clip_inv(&self, o: DVec3, inv: DVec3, t_max: f64) -> Option<(f64, f64)> {
        let ta = (self.min - o) * inv;
        let tb = (self.max - o) * inv;
        let lo = ta.min(tb);
        let hi = ta.max(tb);
        // NaN (0·∞ for rays parallel to a face through it) is ignored by f64::max/min.
        let t0 = lo.x.max(lo.y).max(lo.z).max(0.0);
        let t1 = hi.x.min(hi.y).min(hi.z).min(t_max);
        (t0 <= t1).then_some((t0, t1))
    }
    /// Distance from `p` to the nearest and to the farthest point of the box.
    pub fn distance_range(&self, p: DVec3) -> (f64, f64) {
        let near = p.clamp(self.min, self.max);
        let far = DVec3::new(
            if (p.x - self.min.x).abs() > (p.x - self.max.x).abs() {
                self.min.x
            } else {
                self.max.x
            },
            if (p.y - self.min.y).abs() > (p.y - self.max.y).abs() {
                self.min.y
            } else {
                self.max.y
            },
            if (p.z - self.min.z).abs() > (p.z - self.max.z).abs() {
                self.min.z
            } else {
                self.max.z
            },
        );
        ((p - near).length(), (p - far).length())
    }
}

/// A group of primitives sharing an albedo and a bounding box.
#[derive(Clone, Debug)]
pub struct Object {
    pub albedo: f64,
    pub bounds: Aabb,
    pub prims: Vec<Shape>,
}

impl Object {
    pub fn new(albedo: f64, prims: Vec<Shape>) -> Self {
        let bounds = prims.iter().fold(Aabb::empty(), |b, p| b.union(p.bounds()));
        Object {
            albedo,
            bounds,
            prims,
        }
    }

    /// A fingerprint of the surfaces as rendered (each primitive's corner and edges, bit for bit): for
    /// a mesh, what the scene's text cannot tell, so that an edited OBJ changes a render's key.
    pub fn surface_fingerprint(&self) -> u64 {
        let bits = self.prims.iter().flat_map(|p| {
            let (Shape::Rect { p0, e1, e2, .. } | Shape::Triangle { p0, e1, e2 }) = p;
            [p0, e1, e2]
                .into_iter()
                .flat_map(|v| v.to_array())
                .flat_map(|c| c.to_bits().to_le_bytes())
        });
        crate::hash::fnv1a(bits)
    }
}

/// A surface hit.
#[derive(Clone, Copy, Debug)]
pub struct Hit {
    pub t: f64,
    /// Unit normal facing the incoming ray.
    pub n: DVec3,
    pub albedo: f64,
}

/// What a BVH walk does after a primitive hit.
pub enum Step {
    /// Keep looking with the same range.
    Continue,
    /// Keep looking for hits closer than this one.
    Shrink,
    /// Done.
    Stop,
}

#[derive(Clone, Debug)]
struct Node {
    bounds: Aabb,
    /// A leaf's primitive range, or an interior node's two children.
    a: u32,
    b: u32,
    leaf: bool,
}

/// A bounding volume hierarchy over primitives, each with a caller's tag (median split on the longest
/// axis of the centroids, at most 4 primitives per leaf), so a ray costs O(log n) box tests on OBJ meshes.
#[derive(Clone, Debug, Default)]
pub struct Bvh {
    nodes: Vec<Node>,
    prims: Vec<Shape>,
    tags: Vec<u32>,
}

impl Bvh {
    pub fn new(items: Vec<(Shape, u32)>) -> Self {
        let mut bvh = Bvh::default();
        let mut items: Vec<(Shape, u32, Aabb)> = items
            .into_iter()
            .map(|(s, t)| {
                let b = s.bounds();
                (s, t, b)
            })
            .collect();
        if !items.is_empty() {
            bvh.build(&mut items, 0);
        }
        for (s, t, _) in items {
            bvh.prims.push(s);
            bvh.tags.push(t);
        }
        bvh
    }

    /// Builds the subtree over `items`, which start at `offset` in the final primitive order (they are
    /// reordered in place), and returns its node.
    fn build(&mut self, items: &mut [(Shape, u32, Aabb)], offset: usize) -> u32 {
        let bounds = items.iter().fold(Aabb::empty(), |b, i| b.union(i.2));
        let id = self.nodes.len() as u32;
        self.nodes.push(Node {
            bounds,
            a: offset as u32,
            b: (offset + items.len()) as u32,
            leaf: true,
        });
        if items.len() <= 4 {
            return id;
        }
        let centre = |b: &Aabb| (b.min + b.max) * 0.5;
        let cb = items
            .iter()
            .fold(Aabb::empty(), |b, i| b.grow(centre(&i.2)));
        let ext = cb.max - cb.min;
        let axis = if ext.x >= ext.y && ext.x >= ext.z {
            0
        } else if ext.y >= ext.z {
            1
        } else {
            2
        };
        let mid = items.len() / 2;
        items.select_nth_unstable_by(mid, |p, q| {
            centre(&p.2)[axis].total_cmp(&centre(&q.2)[axis])
        });
        let (lo, hi) = items.split_at_mut(mid);
        let a = self.build(lo, offset);
        let b = self.build(hi, offset + mid);
        self.nodes[id as usize] = Node {
            bounds,
            a,
            b,
            leaf: false,
        };
        id
    }

    /// Visits the primitives hit by `o + t·d`, t ∈ (EPS, t_max), calling `hit(primitive, tag, t)`.
    pub fn walk<'a>(
        &'a self,
        o: DVec3,
        d: DVec3,
        mut t_max: f64,
        mut hit: impl FnMut(&'a Shape, u32, f64) -> Step,
    ) {
        if self.nodes.is_empty() {
            return;
        }
        let inv = d.recip();
        // Depth ≤ log2(n) + 1 for a median split, and each level leaves at most one node on the stack.
        let mut stack = [0u32; 64];
        let mut top = 1;
        while top > 0 {
            top -= 1;
            let n = &self.nodes[stack[top] as usize];
            if n.bounds.clip_inv(o, inv, t_max).is_none() {
                continue;
            }
            if n.leaf {
                for i in n.a as usize..n.b as usize {
                    if let Some(t) = self.prims[i].intersect(o, d, t_max) {
                        match hit(&self.prims[i], self.tags[i], t) {
                            Step::Continue => {}
                            Step::Shrink => t_max = t,
                            Step::Stop => return,
                        }
                    }
                }
            } else {
                stack[top] = n.a;
                stack[top + 1] = n.b;
                top += 2;
            }
        }
    }
}

/// All hidden geometry (the relay surface is handled separately by the integrator).
#[derive(Clone, Debug, Default)]
pub struct Geometry {
    pub objects: Vec<Object>,
    bvh: Bvh,
}

impl Geometry {
    pub fn new(objects: Vec<Object>) -> Self {
        let bvh = Bvh::new(
            objects
                .iter()
                .enumerate()
                .flat_map(|(k, o)| o.prims.iter().map(move |p| (p.clone(), k as u32)))
                .collect(),
        );
        Geometry { objects, bvh }
    }

    pub fn is_empty(&self) -> bool {
        self.objects.iter().all(|o| o.prims.is_empty())
    }

    pub fn bounds(&self) -> Aabb {
        self.objects
            .iter()
            .fold(Aabb::empty(), |b, o| b.union(o.bounds))
    }

    pub fn intersect(&self, o: DVec3, d: DVec3, t_max: f64) -> Option<Hit> {
        let mut best = None;
        self.bvh.walk(o, d, t_max, |p, k, t| {
            best = Some((p, k, t));
            Step::Shrink
        });
        best.map(|(p, k, t)| self.hit(p, k, t, d))
    }

    /// The nearest hit of the ray `o + t·d` (t > EPS) as (object index, t).
    pub fn first_object(&self, o: DVec3, d: DVec3) -> Option<(usize, f64)> {
        let mut best = None;
        self.bvh.walk(o, d, f64::INFINITY, |_, k, t| {
            best = Some((k as usize, t));
            Step::Shrink
        });
        best
    }

    /// Visits every hit of the ray `o + t·d`, t > EPS, as `(primitive, its object, t)`, and returns the
    /// nearest (what `intersect` finds).
    pub fn all_hits(
        &self,
        o: DVec3,
        d: DVec3,
        mut f: impl FnMut(&Shape, &Object, f64),
    ) -> Option<Hit> {
        let mut best: Option<(&Shape, u32, f64)> = None;
        self.bvh.walk(o, d, f64::INFINITY, |p, k, t| {
            f(p, &self.objects[k as usize], t);
            if best.is_none_or(|b| t < b.2) {
                best = Some((p, k, t));
            }
            Step::Continue
        });
        best.map(|(p, k, t)| self.hit(p, k, t, d))
    }

    /// The hit record of primitive `p` of object `k` at `t`, its normal facing the ray.
    fn hit(&self, p: &Shape, k: u32, t: f64, d: DVec3) -> Hit {
        let n = p.normal();
        Hit {
            t,
            n: if n.dot(d) > 0.0 { -n } else { n },
            albedo: self.objects[k as usize].albedo,
        }
    }

    /// Whether anything blocks the open segment `o + t·d`, t ∈ (EPS, t_max − EPS).
    pub fn occluded(&self, o: DVec3, d: DVec3, t_max: f64) -> bool {
        let mut hit = false;
        self.bvh.walk(o, d, t_max - EPS, |_, _, _| {
            hit = true;
            Step::Stop
        });
        hit
    }
}

/// Triangulates a simple polygon (either winding) by ear clipping; returns index triples.
pub fn triangulate(poly: &[[f64; 2]]) -> Vec<[usize; 3]> {
    let n = poly.len();
    let signed_area: f64 = (0..n)
        .map(|i| {
            let (a, b) = (poly[i], poly[(i + 1) % n]);
            a[0] * b[1] - b[0] * a[1]
        })
        .sum();
    let ccw = signed_area > 0.0;
    let cross = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let inside = |p: [f64; 2], a, b, c| {
        cross(a, b, p) >= 0.0 && cross(b, c, p) >= 0.0 && cross(c, a, p) >= 0.0
    };
    let mut idx: Vec<usize> = if ccw {
        (0..n).collect()
    } else {
        (0..n).rev().collect()
    };
    let mut tris = Vec::with_capacity(n.saturating_sub(2));
    while idx.len() > 3 {
        let m = idx.len();
        let ear = (0..m).find(|&i| {
            let (ia, ib, ic) = (idx[(i + m - 1) % m], idx[i], idx[(i + 1) % m]);
            let (a, b, c) = (poly[ia], poly[ib], poly[ic]);
            cross(a, b, c) > 0.0
                && idx
                    .iter()
                    .all(|&j| j == ia || j == ib || j == ic || !inside(poly[j], a, b, c))
        });
        // A degenerate outline has no ear left; stop rather than loop forever.
        let Some(i) = ear else { break };
        tris.push([idx[(i + m - 1) % m], idx[i], idx[(i + 1) % m]]);
        idx.remove(i);
    }
    if idx.len() == 3 {
        tris.push([idx[0], idx[1], idx[2]]);
    }
    tris
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn z_letter_triangulation_keeps_area() {
        let z = murk_synth::z_letter_outline();
        let tris = triangulate(&z);
        assert_eq!(tris.len(), z.len() - 2);
        let shoelace: f64 = 0.5
            * (0..z.len())
                .map(|i| {
                    let (a, b) = (z[i], z[(i + 1) % z.len()]);
                    a[0] * b[1] - b[0] * a[1]
                })
                .sum::<f64>()
                .abs();
        let sum: f64 = tris
            .iter()
            .map(|t| {
                let p = |k: usize| DVec3::new(z[t[k]][0], z[t[k]][1], 0.0);
                0.5 * (p(1) - p(0)).cross(p(2) - p(0)).length()
            })
            .sum();
        // Exact up to rounding: the ears tile the polygon.
        assert!((sum - shoelace).abs() < 1e-12, "{sum} vs {shoelace}");
    }

    /// The BVH answers exactly as brute force over the same primitives: nearest hit (same t), occlusion and
    /// the set of all hits, for 2000 random rays through 500 random triangles and rectangles.
    #[test]
    fn bvh_matches_brute_force() {
        let mut state = 0x9E37_79B9_7F4A_7C15u64;
        let mut rnd = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        fn v3(rnd: &mut impl FnMut() -> f64, s: f64) -> DVec3 {
            DVec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * s
        }
        let prims: Vec<Shape> = (0..500)
            .map(|i| {
                let p0 = v3(&mut rnd, 4.0) + DVec3::new(0.0, 0.0, 3.0);
                let (e1, e2) = (v3(&mut rnd, 0.6), v3(&mut rnd, 0.6));
                if i % 2 == 0 {
                    Shape::Triangle { p0, e1, e2 }
                } else {
                    // Rectangles need e1 ⟂ e2.
                    let e2 = e2 - e1 * (e2.dot(e1) / e1.length_squared());
                    Shape::rect(p0, e1, e2)
                }
            })
            .collect();
        let bvh = Bvh::new(prims.iter().cloned().zip(0..).collect());
        let mut hits = 0;
        for _ in 0..2000 {
            let o = v3(&mut rnd, 2.0);
            let d = (v3(&mut rnd, 1.0) + DVec3::new(0.0, 0.0, 0.7)).normalize();
            let t_max = 1.0 + 6.0 * rnd();
            let brute: Vec<(u32, f64)> = prims
                .iter()
                .zip(0..)
                .filter_map(|(p, k)| p.intersect(o, d, t_max).map(|t| (k, t)))
                .collect();
            let mut all = Vec::new();
            bvh.walk(o, d, t_max, |_, k, t| {
                all.push((k, t));
                Step::Continue
            });
            all.sort_by_key(|h| h.0);
            assert_eq!(all, brute);
            let mut nearest = None;
            bvh.walk(o, d, t_max, |_, _, t| {
                nearest = Some(t);
                Step::Shrink
            });
            let want = brute.iter().map(|h| h.1).min_by(f64::total_cmp);
            assert_eq!(nearest, want);
            hits += brute.len();
        }
        // The rays do meet the geometry (measured: 755 hits), so the comparison is not between empty sets.
        assert!(hits > 500, "{hits} hits");
    }

    #[test]
    fn rect_and_triangle_hits() {
        let r = Shape::rect(DVec3::new(-0.5, -0.5, 1.0), DVec3::X, DVec3::Y);
        assert_eq!(r.intersect(DVec3::ZERO, DVec3::Z, 10.0), Some(1.0));
        assert_eq!(r.intersect(DVec3::new(0.6, 0.0, 0.0), DVec3::Z, 10.0), None);
        let t = Shape::Triangle {
            p0: DVec3::new(0.0, 0.0, 2.0),
            e1: DVec3::X,
            e2: DVec3::Y,
        };
        assert_eq!(
            t.intersect(DVec3::new(0.2, 0.2, 0.0), DVec3::Z, 10.0),
            Some(2.0)
        );
        assert_eq!(t.intersect(DVec3::new(0.6, 0.6, 0.0), DVec3::Z, 10.0), None);
        let b = Aabb::empty()
            .grow(DVec3::splat(-1.0))
            .grow(DVec3::splat(1.0));
        assert_eq!(
            b.clip(DVec3::new(0.0, 0.0, -3.0), DVec3::Z, 100.0),
            Some((2.0, 4.0))
        );
    }
}
