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
//! Gathering ([`gather()`]) uses only the library's public API: the same
//! traversal and microbuffer pipelines a renderer runs.
//!
//! In data-flow order: [`room`](ExactScene::room) builds a scene, `answer` holds
//! its exact values (and the surfels and probes a gather sees), `gather`
//! runs the library on it.

use glam::{DVec3, Vec3};

mod answer;
mod gather;
mod room;

pub use gather::{GatherSettings, Quantity, Stats, gather, gather_with_rays, stats};

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
pub struct ExactScene {
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

#[cfg(test)]
mod tests;
