//! Which triangles may have an opening beside them: those in a flat part of
//! a mesh that ends at a boundary or a crease.
//!
//! A receiver's pixel whose centre ray meets a surface edge-on refines
//! (`microbuffer::open`): its footprint there is long, and a window in that
//! wall may lie in it between the pixels' centres. An opening is bounded by
//! edges: a wall's boundary (a hole in a sheet), a crease (a tunnel through
//! a thick wall, whose jambs meet the wall's face), or a cut-out's texture.
//! A smooth closed surface (a scanned statue) has none, and its curved parts
//! met edge-on cost most of a large mesh's sky rays for nothing. A flat
//! part carries its edges' mark over all of itself, however finely it is
//! tessellated: a window may be many triangles away along a wall.

use std::collections::HashMap;

use glam::Vec3;

/// Neighbours whose normals differ by more than this (cosine: 30°) meet at
/// a crease.
const CREASE: f32 = 0.866;

/// A triangle within this angle (cosine: 1°) of the one that carries an
/// edge's mark lies in the same flat part.
const FLAT: f32 = 0.999_85;

/// No neighbour across that edge.
const NONE: u32 = u32::MAX;

/// Per triangle of `triangles` (three positions each; shared corners are
/// found by position, so split vertices still join), whether it lies in a
/// flat part of the surface that ends at a boundary, a crease or a
/// non-manifold edge, or is degenerate or `cut` (its texture cuts holes).
pub(crate) fn edged(triangles: &[[Vec3; 3]], cut: impl Fn(usize) -> bool) -> Vec<bool> {
    let n = triangles.len();
    let mut corners: HashMap<[u32; 3], u32> = HashMap::with_capacity(n);
    let mut edges = Vec::with_capacity(3 * n);
    let mut normals = Vec::with_capacity(n);
    for (t, tri) in triangles.iter().enumerate() {
        let ids = tri.map(|p| {
            // +0.0 for −0.0: the same point whatever the sign of a zero.
            let key = (p + Vec3::ZERO).to_array().map(f32::to_bits);
            let next = corners.len() as u32;
            *corners.entry(key).or_insert(next)
        });
        for k in 0..3 {
            let (a, b) = (ids[k], ids[(k + 1) % 3]);
            if a != b {
                edges.push((a.min(b), a.max(b), t as u32));
            }
        }
        normals.push((tri[1] - tri[0]).cross(tri[2] - tri[0]).normalize_or_zero());
    }
    edges.sort_unstable();
    let mut mark: Vec<bool> = (0..n).map(|t| cut(t) || normals[t] == Vec3::ZERO).collect();
    let mut across = vec![[NONE; 3]; n];
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && edges[j].0 == edges[i].0 && edges[j].1 == edges[i].1 {
            j += 1;
        }
        let group = &edges[i..j];
        if let [(_, _, s), (_, _, t)] = *group {
            let (s, t) = (s as usize, t as usize);
            if normals[s].dot(normals[t]) < CREASE {
                mark[s] = true;
                mark[t] = true;
            }
            link(&mut across[s], t as u32);
            link(&mut across[t], s as u32);
        } else {
            // A boundary (one triangle) or a non-manifold edge (three or more).
            for &(_, _, t) in group {
                mark[t as usize] = true;
            }
        }
        i = j;
    }
    // Each marked triangle spreads its mark over the neighbours within
    // `FLAT` of its own normal, in index order: the result depends on the
    // mesh alone.
    let mut edged = mark.clone();
    let mut stack = Vec::new();
    for seed in 0..n {
        if !mark[seed] {
            continue;
        }
        let normal = normals[seed];
        stack.push(seed);
        while let Some(t) = stack.pop() {
            for &u in &across[t] {
                let u = u as usize;
                if u != NONE as usize && !edged[u] && normals[u].dot(normal) > FLAT {
                    edged[u] = true;
                    stack.push(u);
                }
            }
        }
    }
    edged
}

/// Records `t` as a neighbour in the first free slot of `slots`.
fn link(slots: &mut [u32; 3], t: u32) {
    if let Some(s) = slots.iter_mut().find(|s| **s == NONE) {
        *s = t;
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::edged;

    /// An `n × n` grid of squares over the unit square at height `z`, two
    /// triangles each, its square `hole` (column, row) left out.
    fn sheet(n: usize, z: f32, hole: Option<(usize, usize)>) -> Vec<[Vec3; 3]> {
        let p = |i: usize, j: usize| Vec3::new(i as f32 / n as f32, j as f32 / n as f32, z);
        let mut t = Vec::new();
        for j in 0..n {
            for i in 0..n {
                if hole == Some((i, j)) {
                    continue;
                }
                t.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                t.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
        t
    }

    /// A UV sphere of `rings × segments`, closed at its poles.
    fn sphere(rings: usize, segments: usize) -> Vec<[Vec3; 3]> {
        let p = |r: usize, s: usize| {
            let (theta, phi) = (
                std::f32::consts::PI * r as f32 / rings as f32,
                std::f32::consts::TAU * (s % segments) as f32 / segments as f32,
            );
            if r == 0 {
                return Vec3::Z;
            }
            if r == rings {
                return -Vec3::Z;
            }
            Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos())
        };
        let mut t = Vec::new();
        for r in 0..rings {
            for s in 0..segments {
                let (a, b, c, d) = (p(r, s), p(r + 1, s), p(r + 1, s + 1), p(r, s + 1));
                if r > 0 {
                    t.push([a, b, d]);
                }
                if r + 1 < rings {
                    t.push([b, c, d]);
                }
            }
        }
        t
    }

    /// A finely tessellated sheet carries its boundary's mark over all of
    /// itself; a closed smooth sphere has no mark; a cut-out triangle has,
    /// and passes it to the other half of its (planar) quad alone.
    #[test]
    fn flat_parts_with_edges_are_edged_and_a_smooth_closed_surface_is_not() {
        let wall = sheet(12, 0.0, Some((6, 6)));
        assert!(edged(&wall, |_| false).iter().all(|&e| e));
        let ball = sphere(24, 48);
        assert!(edged(&ball, |_| false).iter().all(|&e| !e), "a closed sphere");
        let cut = edged(&ball, |t| t == 100);
        assert_eq!(cut.iter().filter(|&&e| e).count(), 2);
        assert!(cut[100] && (cut[99] || cut[101]));
    }

    /// A closed box: every face meets its neighbours at 90°, so a box room
    /// with a tunnel window is edged all through; a sphere's triangles
    /// beside a hole in it are edged, and those far from the hole are not.
    #[test]
    fn creases_and_holes_mark_their_parts_only() {
        let mut cube = Vec::new();
        for (axis, sign) in [(0, 1.0), (0, -1.0), (1, 1.0), (1, -1.0), (2, 1.0), (2, -1.0)] {
            for tri in sheet(3, 0.0, None) {
                cube.push(tri.map(|p| {
                    // The sheet as the face at `axis = sign`, in [−1, 1]³.
                    let (u, v) = (p.x * 2.0 - 1.0, p.y * 2.0 - 1.0);
                    let mut q = [0.0; 3];
                    q[axis] = sign;
                    q[(axis + 1) % 3] = u;
                    q[(axis + 2) % 3] = v;
                    Vec3::from(q)
                }));
            }
        }
        assert!(edged(&cube, |_| false).iter().all(|&e| e), "a box");
        let mut ball = sphere(24, 48);
        let gone = ball.remove(500);
        let marks = edged(&ball, |_| false);
        let near = |t: &[Vec3; 3]| t[0].distance(gone[0]) < 0.3;
        assert!(marks.iter().zip(&ball).any(|(&e, t)| e && near(t)));
        assert!(marks.iter().zip(&ball).all(|(&e, t)| !e || near(t)));
    }
}
