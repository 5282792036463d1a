//! Closed-form references for the gather: rooms of rectangular cells with
//! piecewise-constant radiance, where irradiance and occlusion at any
//! receiver are exact sums of projected solid angles (Lambert's polygon
//! formula), and a glossy lobe is integrated by fine quadrature over the
//! exact radiance field (ray casts against the cells).
//!
//! The room is the box `[−1, 1]³`, `y` up, every wall cut into square cells
//! with a smooth "bounce" radiance per cell and, optionally, a small bright
//! light of 2×2 cells in the middle of the ceiling. Inside a convex room
//! every cell sees every receiver, so the exact answer needs no visibility;
//! an optional slab floating under the light adds one convex occluder whose
//! shadow on the walls is subtracted exactly (the faces of a convex body
//! that face a point have disjoint cones, so their parts add up).
//!
//! Openings: the walls may have a thickness (an outer shell, facing out,
//! lit as a sunlit building is: none of it is seen from inside), a window
//! in the right wall (a tunnel through the wall: four jambs, and the sky
//! beyond), a uniform sky outside and a sunlit patch on the floor. From
//! inside the room, what lies beyond the wall is seen only through the
//! window's inner aperture, and a ray entering the (convex) tunnel leaves it
//! through exactly one jamb or the outer aperture: each part is its
//! polygon clipped to the cone of the inner aperture, and the parts add up.
//!
//! Gathering ([`gather`]) uses only the library's public API: the same
//! traversal and microbuffer pipelines a renderer runs.

use std::sync::Arc;
use std::time::{Duration, Instant};

use glam::{DVec3, Vec3};

use crate::brdf::GlossyLobe;
use crate::environment::Environment;
use crate::microbuffer::{Convolution, MicroBuffer, MicroBufferSink, PacketCut, shade_packet};
use crate::polygon::{clip, projected_solid_angle};
use crate::rng::Rng;
use crate::{CutOptions, Error, LANES, PointCloud, Receiver, Scheme, Surfel, Traversal, Tree};

/// A rectangle `origin + s·e1 + t·e2` (`s, t ∈ [0, 1]`) cut into `cells[0]
/// × cells[1]` cells, emitting towards `e1 × e2`.
#[derive(Clone, Debug)]
pub struct Face {
    /// One corner.
    pub origin: DVec3,
    /// First edge.
    pub e1: DVec3,
    /// Second edge.
    pub e2: DVec3,
    /// Cells along `e1` and `e2`.
    pub cells: [usize; 2],
    /// Radiance of each cell (index `j·cells[0] + i`); `None` is a hole.
    pub radiance: Vec<Option<f64>>,
    /// Whether each cell belongs to the light.
    pub emitter: Vec<bool>,
    /// What the face belongs to, which says how a receiver inside sees it.
    pub part: Part,
}

/// What a [`Face`] belongs to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// A wall of the convex room (inward): seen wherever it faces a receiver.
    Room,
    /// The occluding slab (outward): may hide room cells.
    Blocker,
    /// Beyond the room's walls (a window's jambs, the outer shell): seen
    /// from inside only through the window's inner aperture.
    Beyond,
}

impl Face {
    fn new(origin: DVec3, e1: DVec3, e2: DVec3, cell: f64, part: Part) -> Face {
        let cells = [
            (e1.length() / cell).round().max(1.0) as usize,
            (e2.length() / cell).round().max(1.0) as usize,
        ];
        let count = cells[0] * cells[1];
        Face {
            origin,
            e1,
            e2,
            cells,
            radiance: vec![Some(0.0); count],
            emitter: vec![false; count],
            part,
        }
    }

    /// Unit normal, the side it emits to.
    pub fn normal(&self) -> DVec3 {
        self.e1.cross(self.e2).normalize()
    }

    /// Corners of cell `(i, j)`, counter-clockwise seen from the front.
    fn cell(&self, i: usize, j: usize) -> [DVec3; 4] {
        let (a, b) = (self.e1 / self.cells[0] as f64, self.e2 / self.cells[1] as f64);
        let o = self.origin + a * i as f64 + b * j as f64;
        [o, o + a, o + a + b, o + b]
    }
}

/// What the scene holds besides its bounce-lit walls.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RoomSpec {
    /// Cells per unit length (the room is 2 wide): 8 gives 16×16 cells a wall.
    pub cells_per_unit: usize,
    /// Radiance of the ceiling light (2×2 cells of size 1/8 at the middle
    /// of the ceiling, for `cells_per_unit` 8); 0 for none.
    pub light: f64,
    /// Leave the ceiling out (an open box; the sky is black).
    pub open_ceiling: bool,
    /// Add a slab under the light, an occluder.
    pub blocker: bool,
    /// The walls' thickness: 0 is a single sheet; more adds an outer shell
    /// (facing out) that far out, and the window's four jambs.
    pub wall: f64,
    /// A window [`WINDOW`] in the right wall (`x = 1`).
    pub window: bool,
    /// The uniform sky's radiance outside (0: black).
    pub sky: f64,
    /// The outer shell's radiance (a smooth field about this value; the
    /// roof twice as bright, as under a high sun), and the jambs'.
    pub outside: f64,
    /// The radiance of a sunlit patch on the floor ([`SUN_PATCH`]); 0 for none.
    pub sun_patch: f64,
}

/// The window in the right wall (`x = 1`): `y` from `[0]` to `[1]`, `z`
/// from `[2]` to `[3]`, on cell boundaries for `cells_per_unit` 8 (5×5 cells).
pub const WINDOW: [f64; 4] = [-0.25, 0.375, -0.375, 0.25];

/// The sunlit patch on the floor: `x` from `[0]` to `[1]`, `z` from `[2]`
/// to `[3]` (4×3 cells for `cells_per_unit` 8), where sun through the
/// window would fall.
pub const SUN_PATCH: [f64; 4] = [0.25, 0.75, -0.375, 0.0];

impl Default for RoomSpec {
    fn default() -> Self {
        RoomSpec {
            cells_per_unit: 8,
            light: 200.0,
            open_ceiling: false,
            blocker: false,
            wall: 0.0,
            window: false,
            sky: 0.0,
            outside: 0.0,
            sun_patch: 0.0,
        }
    }
}

/// The rooms with openings, by name: `window` (a window in a single sheet
/// under a uniform sky), `sunroom` (the window through walls 0.075 thick,
/// about 15 cm of a 4 m room, with a sunlit patch on the floor, the sky and
/// the outside lit), `shell` and `thin-shell` (closed walls 0.075 and 0.02
/// thick under the sky, the outside lit: none of the outside's light is
/// seen inside). None has the ceiling light: the walls' own bounce light,
/// the sky and the sun patch light the room.
pub fn opening(name: &str) -> Option<RoomSpec> {
    let base = RoomSpec {
        light: 0.0,
        sky: 2.0,
        ..Default::default()
    };
    Some(match name {
        "window" => RoomSpec { window: true, ..base },
        "sunroom" => RoomSpec {
            window: true,
            wall: 0.075,
            outside: 3.0,
            sun_patch: 10.0,
            ..base
        },
        "shell" => RoomSpec {
            wall: 0.075,
            outside: 3.0,
            ..base
        },
        "thin-shell" => RoomSpec {
            wall: 0.02,
            outside: 3.0,
            ..base
        },
        _ => return None,
    })
}

/// A scene of faces with exact irradiance, occlusion and glossy reflection.
#[derive(Clone, Debug)]
pub struct Scene {
    /// The room's walls (inward), the slab's faces (outward), the jambs
    /// and the outer shell.
    pub faces: Vec<Face>,
    /// The uniform sky's radiance (0: black).
    pub sky: f64,
    /// The window's inner and outer apertures (counter-clockwise seen from
    /// inside), if there is one.
    pub window: Option<[[DVec3; 4]; 2]>,
}

/// A receiver with the direction its glossy reflection is seen from.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Probe {
    /// Position (a hair off the surface, along the normal).
    pub position: Vec3,
    /// Unit normal.
    pub normal: Vec3,
    /// Unit direction to the viewer (the room's centre).
    pub wo: Vec3,
    /// Which face it lies on.
    pub face: &'static str,
    /// `"mid"` (at least 0.4 from every edge of its face), `"edge"` (within
    /// 0.08 of one) or `"corner"` (within 0.08 of two).
    pub class: &'static str,
}

impl Scene {
    /// The room `[−1, 1]³` of `spec`.
    pub fn room(spec: &RoomSpec) -> Scene {
        let cell = 1.0 / spec.cells_per_unit.max(1) as f64;
        let v = DVec3::new;
        let (x2, y2, z2) = (v(2.0, 0.0, 0.0), v(0.0, 2.0, 0.0), v(0.0, 0.0, 2.0));
        // Floor, ceiling, back (z = −1), front, left (x = −1), right: inward.
        let walls = [
            (v(-1.0, -1.0, -1.0), z2, x2, 0.50),
            (v(-1.0, 1.0, -1.0), x2, z2, 0.60),
            (v(-1.0, -1.0, -1.0), x2, y2, 0.40),
            (v(-1.0, -1.0, 1.0), y2, x2, 0.45),
            (v(-1.0, -1.0, -1.0), y2, z2, 0.30),
            (v(1.0, -1.0, -1.0), z2, y2, 0.35),
        ];
        let (mut faces, mut bases) = (Vec::new(), Vec::new());
        for (k, &(o, e1, e2, base)) in walls.iter().enumerate() {
            if k == 1 && spec.open_ceiling {
                continue;
            }
            faces.push(Face::new(o, e1, e2, cell, Part::Room));
            bases.push(base);
        }
        let t = spec.wall.max(0.0);
        let [y0, y1, z0, z1] = WINDOW;
        let window = spec.window.then(|| {
            let at = |x: f64| [v(x, y0, z0), v(x, y1, z0), v(x, y1, z1), v(x, y0, z1)];
            [at(1.0), at(1.0 + t)]
        });
        if t > 0.0 {
            // The outer shell, facing out: the box [−1 − t, 1 + t]³, its
            // right face in four pieces around the window.
            let (lo, s) = (-1.0 - t, 2.0 + 2.0 * t);
            let (ex, ey, ez) = (v(s, 0.0, 0.0), v(0.0, s, 0.0), v(0.0, 0.0, s));
            let o = v(lo, lo, lo);
            let out = spec.outside;
            for (o, e1, e2, base) in [
                (o, ex, ez, out),
                (v(lo, -lo, lo), ez, ex, 2.0 * out),
                (o, ey, ex, out),
                (v(lo, lo, -lo), ex, ey, out),
                (o, ez, ey, out),
            ] {
                faces.push(Face::new(o, e1, e2, cell, Part::Beyond));
                bases.push(base);
            }
            let x = -lo;
            // (y, then z: facing +x.)
            let pieces = if spec.window {
                vec![
                    (v(x, lo, lo), v(0.0, y0 - lo, 0.0), v(0.0, 0.0, s)),
                    (v(x, y1, lo), v(0.0, -lo - y1, 0.0), v(0.0, 0.0, s)),
                    (v(x, y0, lo), v(0.0, y1 - y0, 0.0), v(0.0, 0.0, z0 - lo)),
                    (v(x, y0, z1), v(0.0, y1 - y0, 0.0), v(0.0, 0.0, -lo - z1)),
                ]
            } else {
                vec![(v(x, lo, lo), v(0.0, s, 0.0), v(0.0, 0.0, s))]
            };
            for (o, e1, e2) in pieces {
                faces.push(Face::new(o, e1, e2, cell, Part::Beyond));
                bases.push(out);
            }
            if spec.window {
                // The jambs, facing into the tunnel: sill, head, the two sides.
                let (dx, dy, dz) = (v(t, 0.0, 0.0), v(0.0, y1 - y0, 0.0), v(0.0, 0.0, z1 - z0));
                for (o, e1, e2) in [
                    (v(1.0, y0, z0), dz, dx),
                    (v(1.0, y1, z0), dx, dz),
                    (v(1.0, y0, z0), dx, dy),
                    (v(1.0, y0, z1), dy, dx),
                ] {
                    faces.push(Face::new(o, e1, e2, cell, Part::Beyond));
                    bases.push(0.8 * out.max(0.5));
                }
            }
        }
        if spec.blocker {
            // The slab [−0.37, 0.43] × [0.1, 0.2] × [−0.45, 0.17], faces outward
            // (off the probes' coordinates, so that none sees a face edge-on).
            let (lo, hi) = (v(-0.37, 0.1, -0.45), v(0.43, 0.2, 0.17));
            let d = hi - lo;
            let (ex, ey, ez) = (v(d.x, 0.0, 0.0), v(0.0, d.y, 0.0), v(0.0, 0.0, d.z));
            // Bottom (dim, facing the floor), top (lit), sides.
            for (o, e1, e2, base) in [
                (lo, ex, ez, 0.2),
                (v(lo.x, hi.y, lo.z), ez, ex, 0.8),
                (lo, ey, ex, 0.4),
                (v(lo.x, lo.y, hi.z), ex, ey, 0.4),
                (lo, ez, ey, 0.4),
                (v(hi.x, lo.y, lo.z), ey, ez, 0.4),
            ] {
                faces.push(Face::new(o, e1, e2, cell, Part::Blocker));
                bases.push(base);
            }
        }
        // Whether (x, y) lies inside the rectangle `[x0, x1, y0, y1]`.
        let inside = |x: f64, [a, b, c, d]: [f64; 4], y: f64| a < x && x < b && c < y && y < d;
        for (k, (f, &b)) in faces.iter_mut().zip(&bases).enumerate() {
            let phase = k as f64;
            for j in 0..f.cells[1] {
                for i in 0..f.cells[0] {
                    let c = f.cell(i, j);
                    let m = (c[0] + c[2]) * 0.5;
                    // Smooth bounce light, varying per cell so that clusters average it.
                    let l = b * (1.0 + 0.3 * (2.1 * m.x + 1.3 * m.y + 0.7 * m.z + phase).sin());
                    let room = f.part == Part::Room;
                    let light = room
                        && spec.light > 0.0
                        && (m.y - 1.0).abs() < 1e-9
                        && m.x.abs() < 0.125
                        && m.z.abs() < 0.125;
                    let hole = room && spec.window && (m.x - 1.0).abs() < 1e-9 && inside(m.y, WINDOW, m.z);
                    let sun = room
                        && spec.sun_patch > 0.0
                        && (m.y + 1.0).abs() < 1e-9
                        && inside(m.x, SUN_PATCH, m.z);
                    let c = j * f.cells[0] + i;
                    f.radiance[c] = match (hole, light, sun) {
                        (true, _, _) => None,
                        (_, true, _) => Some(spec.light),
                        (_, _, true) => Some(spec.sun_patch),
                        _ => Some(l),
                    };
                    f.emitter[c] = light;
                }
            }
        }
        Scene {
            faces,
            sky: spec.sky.max(0.0),
            window,
        }
    }

    /// The same scene with the room's own walls (and the slab) black: what
    /// lights it comes from beyond the walls (the sky and the jambs through
    /// the window, nothing of the outer shell).
    pub fn dark_inside(&self) -> Scene {
        let mut s = self.clone();
        for f in s.faces.iter_mut().filter(|f| f.part != Part::Beyond) {
            f.radiance.iter_mut().flatten().for_each(|l| *l = 0.0);
        }
        s
    }

    /// The same scene with the light's cells cut out (holes: they neither
    /// emit nor occlude), for the bounce light alone.
    pub fn without_emitter(&self) -> Scene {
        let mut s = self.clone();
        for f in &mut s.faces {
            for (r, &e) in f.radiance.iter_mut().zip(&f.emitter) {
                if e {
                    *r = None;
                }
            }
        }
        s
    }

    /// Surfels: each cell cut into `per_cell × per_cell` squares, one surfel
    /// in each (at a jittered point when `seed` is given, else the centre),
    /// of the square's area, the cell's radiance, the face's normal.
    pub fn surfels(&self, per_cell: usize, seed: Option<u64>) -> Vec<Surfel> {
        let k = per_cell.max(1);
        let mut rng = Rng::new(seed.unwrap_or(0));
        let mut out = Vec::new();
        for f in &self.faces {
            let n = f.normal().as_vec3();
            let (a, b) = (f.e1 / (f.cells[0] * k) as f64, f.e2 / (f.cells[1] * k) as f64);
            let radius = (a.cross(b).length() / std::f64::consts::PI).sqrt() as f32;
            for j in 0..f.cells[1] * k {
                for i in 0..f.cells[0] * k {
                    let Some(l) = f.radiance[(j / k) * f.cells[0] + i / k] else {
                        continue;
                    };
                    let (u, v) = match seed {
                        Some(_) => (rng.f32() as f64, rng.f32() as f64),
                        None => (0.5, 0.5),
                    };
                    let p = f.origin + a * (i as f64 + u) + b * (j as f64 + v);
                    out.push(Surfel {
                        position: p.as_vec3(),
                        normal: n,
                        radius,
                        radiance: Vec3::splat(l as f32),
                    });
                }
            }
        }
        out
    }

    /// The tree of [`surfels`](Self::surfels).
    pub fn tree(&self, per_cell: usize, seed: Option<u64>) -> Result<Tree, Error> {
        Ok(Tree::build(&PointCloud::new(self.surfels(per_cell, seed))?))
    }

    /// Receivers on the floor, back wall, right wall and ceiling (36 each):
    /// a 6×6 grid of face coordinates from 0.005 (0.01 from the edge; in a
    /// corner two walls are seen edge-on) over mid-wall to 0.96, `offset`
    /// off the surface along the normal (the renderer moves camera hits
    /// 10⁻⁵ of the scene size off their surface). With a window, those in
    /// it are left out, those within 0.1 of it are of class `"window"`, and
    /// twelve more stand near it: 0.02 and 0.06 off the middle of each of
    /// its edges on the wall, and four on the floor below and before it.
    pub fn probes(&self, offset: f32) -> Vec<Probe> {
        let st = [0.005, 0.04, 0.2, 0.45, 0.7, 0.96];
        let near = |x: f64| !(0.1..=0.9).contains(&x);
        let v = DVec3::new;
        let walls = [
            ("floor", v(-1.0, -1.0, -1.0), v(0.0, 0.0, 2.0), v(2.0, 0.0, 0.0)),
            ("back", v(-1.0, -1.0, -1.0), v(2.0, 0.0, 0.0), v(0.0, 2.0, 0.0)),
            ("right", v(1.0, -1.0, -1.0), v(0.0, 0.0, 2.0), v(0.0, 2.0, 0.0)),
            ("ceiling", v(-1.0, 1.0, -1.0), v(2.0, 0.0, 0.0), v(0.0, 0.0, 2.0)),
        ];
        let [y0, y1, z0, z1] = WINDOW;
        // How far a point of the right wall lies outside the window (< 0: in it).
        let off_window = |q: DVec3| (y0 - q.y).max(q.y - y1).max(z0 - q.z).max(q.z - z1);
        let mut out = Vec::new();
        let mut push = |name, q: DVec3, n: Vec3, class| {
            let p = q.as_vec3() + n * offset;
            out.push(Probe {
                position: p,
                normal: n,
                wo: (-p).normalize(),
                face: name,
                class,
            });
        };
        for (name, o, e1, e2) in walls {
            let n = e1.cross(e2).normalize().as_vec3();
            for &t in &st {
                for &s in &st {
                    let q = o + e1 * s + e2 * t;
                    let mut class = ["mid", "edge", "corner"][usize::from(near(s)) + usize::from(near(t))];
                    if self.window.is_some() && name == "right" {
                        match off_window(q) {
                            d if d <= 0.0 => continue,
                            d if d < 0.1 => class = "window",
                            _ => {}
                        }
                    }
                    push(name, q, n, class);
                }
            }
        }
        if self.window.is_some() {
            let (ym, zm) = ((y0 + y1) * 0.5, (z0 + z1) * 0.5);
            for d in [0.02, 0.06] {
                for q in [
                    v(1.0, y0 - d, zm),
                    v(1.0, y1 + d, zm),
                    v(1.0, ym, z0 - d),
                    v(1.0, ym, z1 + d),
                ] {
                    push("right", q, Vec3::NEG_X, "window");
                }
            }
            for x in [0.98, 0.9, 0.7, 0.4] {
                push("floor", v(x, -1.0, zm + 0.03), Vec3::Y, "window");
            }
        }
        out
    }

    /// Exact irradiance (`∫ L cosθ dω`) and occlusion (`∫ cosθ dω / π` over
    /// the directions some cell covers) at `p` (inside the room) facing `n`;
    /// the sky adds to irradiance, not to occlusion.
    pub fn exact(&self, p: Vec3, n: Vec3) -> (f64, f64) {
        let (p, n) = (p.as_dvec3(), n.as_dvec3());
        // The cone (edge planes through p, inward) of a convex polygon.
        let cone = |c: [DVec3; 4]| -> [DVec3; 4] {
            let c = c.map(|q| q - p);
            let mid = (c[0] + c[2]) * 0.5;
            std::array::from_fn(|k| {
                let m = c[k].cross(c[(k + 1) % 4]);
                if m.dot(mid) < 0.0 { -m } else { m }
            })
        };
        let within =
            |poly: Vec<DVec3>, cone: &[DVec3; 4]| cone.iter().fold(poly, |part, m| clip(&part, |q| m.dot(q)));
        // Cones of the slab faces p sees.
        let cones: Vec<[DVec3; 4]> = self
            .faces
            .iter()
            .filter(|f| f.part == Part::Blocker && (p - f.origin).dot(f.normal()) > 1e-7)
            .map(|f| cone([f.origin, f.origin + f.e1, f.origin + f.e1 + f.e2, f.origin + f.e2]))
            .collect();
        // The projected solid angle of `poly` (relative to p) less what the
        // slab hides of it.
        let seen = |poly: Vec<DVec3>| {
            let mut w = projected_solid_angle(&poly, n);
            for c in &cones {
                w -= projected_solid_angle(&within(poly.clone(), c), n);
            }
            w
        };
        let aperture = self.window.map(|[inner, _]| cone(inner));
        let (mut e, mut covered) = (0.0, 0.0);
        for f in &self.faces {
            if (p - f.origin).dot(f.normal()) <= 0.0 {
                continue; // p is behind it (or on its plane)
            }
            let through = match (f.part, aperture) {
                (Part::Beyond, None) => continue,
                (Part::Beyond, Some(a)) => Some(a),
                _ => None,
            };
            for j in 0..f.cells[1] {
                for i in 0..f.cells[0] {
                    let Some(l) = f.radiance[j * f.cells[0] + i] else {
                        continue;
                    };
                    let mut poly = clip(&f.cell(i, j).map(|q| q - p), |q| n.dot(q));
                    if let Some(a) = &through {
                        poly = within(poly, a);
                    }
                    let w = if f.part == Part::Blocker {
                        projected_solid_angle(&poly, n)
                    } else {
                        seen(poly)
                    };
                    e += l * w;
                    covered += w;
                }
            }
        }
        if let (Some([_, outer]), Some(a)) = (self.window, &aperture)
            && self.sky > 0.0
        {
            let poly = clip(&outer.map(|q| q - p), |q| n.dot(q));
            e += self.sky * seen(within(poly, a));
        }
        (e, covered / std::f64::consts::PI)
    }

    /// The nearest cell hit from its front along unit `d` from `p` (holes
    /// let the ray through): face, cell index and distance.
    fn hit(&self, p: DVec3, d: DVec3) -> Option<(usize, usize, f64)> {
        let mut best: Option<(usize, usize, f64)> = None;
        for (k, f) in self.faces.iter().enumerate() {
            let nrm = f.normal();
            let den = d.dot(nrm);
            let t = (f.origin - p).dot(nrm) / den;
            if den >= 0.0 || !(t > 0.0 && best.is_none_or(|b| t < b.2)) {
                continue;
            }
            let q = p + d * t - f.origin;
            let (s, u) = (
                q.dot(f.e1) / f.e1.length_squared(),
                q.dot(f.e2) / f.e2.length_squared(),
            );
            if !((0.0..1.0).contains(&s) && (0.0..1.0).contains(&u)) {
                continue;
            }
            let c = (u * f.cells[1] as f64) as usize * f.cells[0] + (s * f.cells[0] as f64) as usize;
            if f.radiance[c].is_some() {
                best = Some((k, c, t));
            }
        }
        best
    }

    /// Radiance seen from `p` along unit `d`; the sky's where the ray leaves.
    pub fn radiance(&self, p: DVec3, d: DVec3) -> f64 {
        self.hit(p, d)
            .map_or(self.sky, |(k, c, _)| self.faces[k].radiance[c].unwrap_or(0.0))
    }

    /// Glossy reflection `∫ f_s(ωi, wo) L(ωi) cosθi dωi` of `lobe` at `p`
    /// facing `n`. The light's small bright cells would alias on any
    /// direction grid, so they are integrated over their area (96 × 96
    /// midpoints a cell, each with a visibility ray: fine enough for a slab
    /// edge across the light, 0.1 %); the rest of the field
    /// by an `m × m` midpoint rule in the lobe's own sampling map (weights
    /// `f_s·cosθ / pdf`, the lobe's exact shape), the light's cells black.
    pub fn glossy(&self, p: Vec3, n: Vec3, wo: Vec3, lobe: &GlossyLobe, m: usize) -> f64 {
        let (p, n, wo) = (p.as_dvec3(), n.as_dvec3(), wo.as_dvec3());
        let r = 2.0 * n.dot(wo) * n - wo;
        let e = lobe.exponent() as f64;
        let spec = lobe.specular.x as f64;
        let (t, b) = r.any_orthonormal_pair();
        let mut sum = 0.0;
        for i in 0..m {
            let cos = ((i as f64 + 0.5) / m as f64).powf(1.0 / (e + 1.0));
            let sin = (1.0 - cos * cos).max(0.0).sqrt();
            for j in 0..m {
                let phi = std::f64::consts::TAU * (j as f64 + 0.5) / m as f64;
                let wi = t * (sin * phi.cos()) + b * (sin * phi.sin()) + r * cos;
                let c = wi.dot(n);
                if c > 0.0 {
                    sum += c * match self.hit(p, wi) {
                        Some((k, cell, _)) if self.faces[k].emitter[cell] => 0.0,
                        Some((k, cell, _)) => self.faces[k].radiance[cell].unwrap_or(0.0),
                        None => self.sky,
                    };
                }
            }
        }
        let mut glossy = sum * spec * (e + 2.0) / (e + 1.0) / (m * m) as f64;
        let g = 96;
        for (k, f) in self.faces.iter().enumerate() {
            let (a, bb) = (f.e1 / f.cells[0] as f64, f.e2 / f.cells[1] as f64);
            let da = a.cross(bb).length() / (g * g) as f64;
            for (cell, l) in f.radiance.iter().enumerate() {
                let (Some(l), true) = (l, f.emitter[cell]) else {
                    continue;
                };
                let o = f.origin + a * (cell % f.cells[0]) as f64 + bb * (cell / f.cells[0]) as f64;
                for s in 0..g {
                    for u in 0..g {
                        let q = o + a * ((s as f64 + 0.5) / g as f64) + bb * ((u as f64 + 0.5) / g as f64);
                        let (v, d2) = ((q - p).normalize(), (q - p).length_squared());
                        let (ci, co) = (v.dot(n), -v.dot(f.normal()));
                        let seen = self.hit(p, v).is_some_and(|h| h.0 == k && h.1 == cell);
                        let cr = r.dot(v);
                        if ci > 0.0 && co > 0.0 && cr > 0.0 && seen {
                            let fs = spec * (e + 2.0) / std::f64::consts::TAU * cr.powf(e);
                            glossy += l * fs * ci * co / d2 * da;
                        }
                    }
                }
            }
        }
        glossy
    }
}

/// What a gather computes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Quantity {
    /// Irradiance (first channel).
    Irradiance,
    /// Ambient occlusion.
    Occlusion,
    /// Glossy reflection towards each probe's `wo` (scalar pipeline only:
    /// the 16-lane one has no glossy convolution).
    Glossy(GlossyLobe),
}

/// How to gather.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gather {
    /// Ω of the cut.
    pub max_solid_angle: f32,
    /// The weight of a node's light offset in the cut
    /// ([`CutOptions::light_offset`]).
    pub light_offset: f32,
    /// Microbuffer resolution N.
    pub resolution: usize,
    /// The 16-lane shading pipeline ([`shade_packet`], what the renderer
    /// runs) rather than the scalar one ([`MicroBufferSink`]).
    pub lanes: bool,
    /// Traversal scheme.
    pub scheme: Scheme,
    /// The uniform sky the open pixels see (the scene's [`Scene::sky`]).
    pub sky: f32,
}

/// Gathers `what` at every probe, on this thread; returns the values and
/// the time taken (traversal, splatting and convolution).
pub fn gather(
    tree: &Tree,
    probes: &[Probe],
    what: Quantity,
    g: &Gather,
) -> Result<(Vec<f64>, Duration), Error> {
    let t = Traversal::new(
        tree,
        CutOptions {
            max_solid_angle: g.max_solid_angle,
            light_offset: g.light_offset,
            ..Default::default()
        },
    )?;
    let receivers = Receiver::from_pairs(probes.iter().map(|p| (p.position, p.normal)))?;
    let sky = (g.sky > 0.0)
        .then(|| Environment::uniform(Vec3::splat(g.sky)).map(Arc::new))
        .transpose()?;
    let mut bufs = vec![MicroBuffer::new(g.resolution)?.with_environment(sky); LANES];
    let mut cut = PacketCut::new(tree);
    let mut out = Vec::with_capacity(probes.len());
    let mut values = [Vec3::ZERO; LANES];
    let start = Instant::now();
    for (chunk, pr) in receivers.chunks(LANES).zip(probes.chunks(LANES)) {
        let bufs = &mut bufs[..chunk.len()];
        for (b, r) in bufs.iter_mut().zip(chunk) {
            b.reset(r.position(), r.normal());
        }
        let conv = match what {
            Quantity::Irradiance => Convolution::Irradiance,
            _ => Convolution::Occlusion,
        };
        if g.lanes && !matches!(what, Quantity::Glossy(_)) {
            t.run(g.scheme, chunk, &mut cut);
            shade_packet(t.isa(), bufs, tree, &mut cut, conv, &mut values)?;
            out.extend(values[..chunk.len()].iter().map(|v| v.x as f64));
        } else {
            t.run(g.scheme, chunk, &mut MicroBufferSink { tree, buffers: bufs });
            out.extend(bufs.iter().zip(pr).map(|(b, p)| match what {
                Quantity::Irradiance => b.irradiance(tree).x as f64,
                Quantity::Occlusion => b.occlusion(tree) as f64,
                Quantity::Glossy(lobe) => b.glossy(tree, p.wo, &lobe).x as f64,
            }));
        }
    }
    Ok((out, start.elapsed()))
}

/// Error of gathered values against exact ones, relative per receiver.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    /// `√ mean((g − e)/e)²`.
    pub rel_rmse: f64,
    /// `mean (g − e)/e`.
    pub bias: f64,
    /// `max |g − e|/e`.
    pub max: f64,
}

/// [`Stats`] of `gathered` against `exact` (receivers with `exact ≤ 0` are skipped).
pub fn stats(gathered: &[f64], exact: &[f64]) -> Stats {
    let (mut s2, mut s1, mut max, mut n) = (0.0, 0.0, 0.0f64, 0usize);
    for (&g, &e) in gathered.iter().zip(exact) {
        if e > 0.0 {
            let r = (g - e) / e;
            s2 += r * r;
            s1 += r;
            max = max.max(r.abs());
            n += 1;
        }
    }
    let n = n.max(1) as f64;
    Stats {
        rel_rmse: (s2 / n).sqrt(),
        bias: s1 / n,
        max,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_closed_room_occludes_everything_and_an_open_one_the_sky_exactly() {
        let closed = Scene::room(&RoomSpec::default());
        let open = Scene::room(&RoomSpec {
            open_ceiling: true,
            ..Default::default()
        });
        for p in closed.probes(2e-5) {
            let (_, occ) = closed.exact(p.position, p.normal);
            assert!((occ - 1.0).abs() < 1e-9, "{p:?}: {occ}");
        }
        // On the floor's centre the opening (2×2 at height 2) has form factor
        // a²/(a² + h²)-like closed form for a square: check by quadrature.
        let p = Vec3::new(0.0, -1.0 + 2e-5, 0.0);
        let (_, occ) = open.exact(p, Vec3::Y);
        let (mut sky, m) = (0.0, 2000);
        for i in 0..m {
            for j in 0..m {
                // Cosine-weighted midpoint rule over the disk.
                let (r, phi) = (
                    ((i as f64 + 0.5) / m as f64).sqrt(),
                    std::f64::consts::TAU * (j as f64 + 0.5) / m as f64,
                );
                let d = DVec3::new(r * phi.cos(), (1.0 - r * r).sqrt(), r * phi.sin());
                let q = p.as_dvec3() + d * ((1.0 - p.y as f64) / d.y);
                sky += f64::from(q.x.abs() < 1.0 && q.z.abs() < 1.0);
            }
        }
        let exact_sky = sky / (m * m) as f64;
        assert!(
            (1.0 - occ - exact_sky).abs() < 1e-3,
            "{} vs {exact_sky}",
            1.0 - occ
        );
    }

    #[test]
    fn through_a_window_lambert_matches_quadrature() {
        // The jambs, the sky and the sunlit patch seen through the window's
        // inner aperture, clipped, against rays (which know nothing of
        // apertures: they pass the hole and meet a jamb or leave).
        let flat = GlossyLobe {
            specular: glam::Vec3::ONE,
            roughness: 1.0,
        };
        for name in ["window", "sunroom"] {
            let s = Scene::room(&opening(name).expect("a scene"));
            let probes = s.probes(2e-5);
            let mut sky = 0;
            for p in probes
                .iter()
                .filter(|p| p.class == "window" || p.face == "floor")
                .step_by(3)
            {
                let (e, _) = s.exact(p.position, p.normal);
                let q = s.glossy(p.position, p.normal, p.normal, &flat, 600) * std::f64::consts::PI;
                assert!((q / e - 1.0).abs() < 5e-3, "{name} {p:?}: {e} vs {q}");
                let dark = Scene {
                    faces: Vec::new(),
                    ..s.clone()
                };
                sky += usize::from(dark.glossy(p.position, p.normal, p.normal, &flat, 8) > 0.0);
            }
            assert!(sky >= 5, "{name}: too few receivers see the sky ({sky})");
        }
    }

    #[test]
    fn a_thick_walled_room_sees_none_of_its_outside() {
        for name in ["shell", "thin-shell", "sunroom"] {
            let lit = Scene::room(&opening(name).expect("a scene"));
            let mut dark = lit.dark_inside();
            dark.sky = 0.0;
            for p in dark.probes(2e-5) {
                let (e, occ) = dark.exact(p.position, p.normal);
                if dark.window.is_none() {
                    assert_eq!(e, 0.0, "{name} {p:?}");
                    assert!((occ - 1.0).abs() < 1e-9, "{name} {p:?}: {occ}");
                }
                // Only the jambs, through the window: at most their
                // brightest (0.8 of the outside, ±30 %) over the hemisphere.
                assert!(
                    e >= 0.0 && e < 0.8 * 3.0 * 1.3 * std::f64::consts::PI,
                    "{name} {p:?}: {e}"
                );
            }
        }
    }

    #[test]
    fn lambert_matches_quadrature_with_and_without_the_blocker() {
        for blocker in [false, true] {
            let s = Scene::room(&RoomSpec {
                blocker,
                ..Default::default()
            });
            let flat = GlossyLobe {
                specular: glam::Vec3::ONE,
                roughness: 1.0,
            }; // e = 0: f·cos/pdf = 2 cos
            for p in s.probes(2e-5).iter().step_by(5) {
                let (e, _) = s.exact(p.position, p.normal);
                // The flat lobe about the mirror direction of the normal is the
                // uniform hemisphere: ∫ 2cosθ L dω / 2π·... = E/π.
                let q = s.glossy(p.position, p.normal, p.normal, &flat, 600);
                assert!(
                    (q * std::f64::consts::PI / e - 1.0).abs() < 5e-3,
                    "blocker {blocker} {p:?}: {e} vs {}",
                    q * std::f64::consts::PI
                );
            }
        }
    }
}
