//! A bounding volume hierarchy over a mesh's triangles, for the two queries a mesh's signed distance
//! needs: the closest point ([`Bvh::closest`]) and, through the per-node sums of
//! [`super::winding`], the generalised winding number. Written here because the closest-point query
//! with a known upper bound (the lattice neighbour's distance plus the step, which prunes almost the
//! whole tree) and per-node moments are what the general-purpose BVH crates, built for rays, lack.
//!
//! Built top-down by splitting at the median centroid along the longest axis of the node's centroid
//! box, down to [`LEAF_SIZE`] triangles; nodes are stored depth-first, so a node's left child follows
//! it and every node's triangles are one contiguous range of [`Bvh::triangles`].

use glam::Vec3;

/// Most triangles in a leaf.
pub const LEAF_SIZE: usize = 4;

/// A node of the tree.
#[derive(Clone, Copy, Debug)]
pub struct Node {
    /// Lower corner of the box of its triangles.
    pub lo: Vec3,
    /// Upper corner.
    pub hi: Vec3,
    /// First triangle of the node's range in [`Bvh::triangles`].
    pub start: u32,
    /// Number of triangles in the node's subtree.
    pub count: u32,
    /// Index of the right child (the left one is the next node); 0 for a leaf.
    pub right: u32,
}

impl Node {
    /// True for a leaf.
    #[inline]
    pub fn is_leaf(&self) -> bool {
        self.right == 0
    }

    /// Squared distance from `q` to the node's box (0 inside).
    #[inline]
    fn distance2(&self, q: Vec3) -> f32 {
        let d = (self.lo - q).max(q - self.hi).max(Vec3::ZERO);
        d.length_squared()
    }
}

/// The tree, with the triangles' corners in leaf order.
#[derive(Clone, Debug)]
pub struct Bvh {
    /// Nodes, the root first.
    pub nodes: Vec<Node>,
    /// Corners of each triangle, in the order of the leaves.
    pub triangles: Vec<[Vec3; 3]>,
    /// The mesh's index of each of [`Bvh::triangles`].
    pub ids: Vec<u32>,
}

/// The closest point of a mesh to a query point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Closest {
    /// Squared distance.
    pub distance2: f32,
    /// The point on the mesh.
    pub point: Vec3,
    /// The mesh's index of the triangle it lies on.
    pub face: u32,
    /// The triangle's place in [`Bvh::triangles`] (a hint for [`Bvh::closest_near`]).
    pub slot: u32,
}

impl Bvh {
    /// The tree over the triangles `faces` of `vertices` (indices must be in range).
    pub fn new(vertices: &[Vec3], faces: &[[u32; 3]]) -> Self {
        let corners: Vec<[Vec3; 3]> = (faces.iter())
            .map(|f| f.map(|i| vertices[i as usize]))
            .collect();
        let mut items: Vec<(Vec3, u32)> = (corners.iter().enumerate())
            .map(|(k, t)| ((t[0] + t[1] + t[2]) / 3.0, k as u32))
            .collect();
        let mut nodes = Vec::with_capacity(2 * faces.len() / LEAF_SIZE + 1);
        build(&corners, &mut items, 0, &mut nodes);
        let triangles = items.iter().map(|&(_, k)| corners[k as usize]).collect();
        let ids = items.iter().map(|&(_, k)| k).collect();
        Self {
            nodes,
            triangles,
            ids,
        }
    }

    /// The point of the mesh closest to `q`, if one lies closer than `sqrt(bound2)` (pass
    /// `f32::INFINITY` for any). With a tight bound most of the tree is never visited.
    pub fn closest(&self, q: Vec3, bound2: f32) -> Option<Closest> {
        self.search(q, None, bound2)
    }

    /// The point of the mesh closest to `q`, starting from the triangle at `slot` of
    /// [`Bvh::triangles`] (e.g. the closest one of a neighbouring query): its distance bounds the
    /// search from the start, so that only the few triangles that could be closer are visited.
    pub fn closest_near(&self, q: Vec3, slot: u32) -> Closest {
        let k = (slot as usize).min(self.triangles.len() - 1);
        let p = closest_on_triangle(q, &self.triangles[k]);
        let hint = Closest {
            distance2: (p - q).length_squared(),
            point: p,
            face: self.ids[k],
            slot: k as u32,
        };
        // Any triangle as close as the hint would do: search strictly closer ones.
        self.search(q, Some(hint), hint.distance2).unwrap_or(hint)
    }

    fn search(&self, q: Vec3, start: Option<Closest>, bound2: f32) -> Option<Closest> {
        let mut best: Option<Closest> = start;
        let mut best2 = bound2;
        let mut stack: [(u32, f32); 64] = [(0, 0.0); 64];
        let mut top = 1;
        stack[0] = (0, self.nodes[0].distance2(q));
        while top > 0 {
            top -= 1;
            let (n, d2) = stack[top];
            if d2 >= best2 {
                continue;
            }
            let node = &self.nodes[n as usize];
            if node.is_leaf() {
                let range = node.start as usize..(node.start + node.count) as usize;
                for k in range {
                    let t = &self.triangles[k];
                    // The triangle's box first: most triangles of a visited leaf are farther.
                    let (lo, hi) = (t[0].min(t[1]).min(t[2]), t[0].max(t[1]).max(t[2]));
                    if (lo - q).max(q - hi).max(Vec3::ZERO).length_squared() >= best2 {
                        continue;
                    }
                    let p = closest_on_triangle(q, t);
                    let e2 = (p - q).length_squared();
                    if e2 < best2 {
                        best2 = e2;
                        best = Some(Closest {
                            distance2: e2,
                            point: p,
                            face: self.ids[k],
                            slot: k as u32,
                        });
                    }
                }
                continue;
            }
            let (l, r) = (n + 1, node.right);
            let (dl, dr) = (
                self.nodes[l as usize].distance2(q),
                self.nodes[r as usize].distance2(q),
            );
            // The nearer child is visited first (pushed last).
            let (near, far) = if dl <= dr {
                ((l, dl), (r, dr))
            } else {
                ((r, dr), (l, dl))
            };
            if far.1 < best2 {
                stack[top] = far;
                top += 1;
            }
            if near.1 < best2 {
                stack[top] = near;
                top += 1;
            }
        }
        best
    }
}

/// Builds the subtree of `items[..]` (whose first triangle is number `start`) and returns its index.
fn build(
    corners: &[[Vec3; 3]],
    items: &mut [(Vec3, u32)],
    start: u32,
    nodes: &mut Vec<Node>,
) -> u32 {
    let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    let (mut clo, mut chi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    for &(c, k) in items.iter() {
        for v in corners[k as usize] {
            lo = lo.min(v);
            hi = hi.max(v);
        }
        clo = clo.min(c);
        chi = chi.max(c);
    }
    let index = nodes.len() as u32;
    nodes.push(Node {
        lo,
        hi,
        start,
        count: items.len() as u32,
        right: 0,
    });
    let extent = chi - clo;
    // A leaf when small, or when every centroid coincides (no split separates them).
    if items.len() <= LEAF_SIZE || extent.max_element() <= 0.0 {
        return index;
    }
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| a.0[axis].total_cmp(&b.0[axis]));
    let (left, right) = items.split_at_mut(mid);
    build(corners, left, start, nodes);
    let r = build(corners, right, start + mid as u32, nodes);
    nodes[index as usize].right = r;
    index
}

/// The point of triangle `t` closest to `q` (Ericson, *Real-Time Collision Detection*, §5.1.5, by
/// Voronoi regions); a degenerate triangle falls back to the closest of its edges.
pub fn closest_on_triangle(q: Vec3, t: &[Vec3; 3]) -> Vec3 {
    let [a, b, c] = *t;
    let (ab, ac, ap) = (b - a, c - a, q - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = q - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = q - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let sum = va + vb + vc;
    let p = a + ab * (vb / sum) + ac * (vc / sum);
    if p.is_finite() {
        return p;
    }
    // Degenerate (zero area, or overflow): the nearest point of the three edges.
    [(a, b), (b, c), (c, a)]
        .map(|(u, v)| closest_on_segment(q, u, v))
        .into_iter()
        .min_by(|x, y| {
            (*x - q)
                .length_squared()
                .total_cmp(&(*y - q).length_squared())
        })
        .unwrap_or(a)
}

/// The point of segment `[u, v]` closest to `q`.
fn closest_on_segment(q: Vec3, u: Vec3, v: Vec3) -> Vec3 {
    let e = v - u;
    let l2 = e.length_squared();
    if l2 <= 0.0 {
        return u;
    }
    u + e * ((q - u).dot(e) / l2).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force against the tree on a cloud of random triangles.
    #[test]
    fn closest_matches_brute_force() {
        let mut state = 12345u64;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 40) as f32 / (1u64 << 24) as f32) * 2.0 - 1.0
        };
        let vertices: Vec<Vec3> = (0..300)
            .map(|_| Vec3::new(next(), next(), next()))
            .collect();
        let faces: Vec<[u32; 3]> = (0..100).map(|k| [3 * k, 3 * k + 1, 3 * k + 2]).collect();
        let bvh = Bvh::new(&vertices, &faces);
        for _ in 0..200 {
            let q = Vec3::new(next(), next(), next()) * 1.5;
            let brute = (faces.iter())
                .map(|f| {
                    let p = closest_on_triangle(q, &f.map(|i| vertices[i as usize]));
                    (p - q).length_squared()
                })
                .fold(f32::INFINITY, f32::min);
            let got = bvh.closest(q, f32::INFINITY).unwrap();
            assert!(
                (got.distance2 - brute).abs() <= 1e-6 * brute.max(1e-3),
                "{got:?} {brute}"
            );
        }
    }

    #[test]
    fn degenerate_triangles_have_a_closest_point() {
        let t = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0];
        let p = closest_on_triangle(Vec3::new(1.5, 1.0, 0.0), &t);
        assert!((p - Vec3::new(1.5, 0.0, 0.0)).length() < 1e-6, "{p}");
        let point = [Vec3::ONE; 3];
        assert_eq!(closest_on_triangle(Vec3::ZERO, &point), Vec3::ONE);
    }
}
