//! Building the room: its walls, the slab, the window's tunnel and the outer shell.

use glam::DVec3;

use super::{ExactScene, Face, Part, RoomSpec, SUN_PATCH, WINDOW};

impl ExactScene {
    /// The room `[−1, 1]³` of `spec`.
    pub fn room(spec: &RoomSpec) -> ExactScene {
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
        ExactScene {
            faces,
            sky: spec.sky.max(0.0),
            window,
        }
    }

    /// The same scene with the room's own walls (and the slab) black: what
    /// lights it comes from beyond the walls (the sky and the jambs through
    /// the window, nothing of the outer shell).
    pub fn dark_inside(&self) -> ExactScene {
        let mut s = self.clone();
        for f in s.faces.iter_mut().filter(|f| f.part != Part::Beyond) {
            f.radiance.iter_mut().flatten().for_each(|l| *l = 0.0);
        }
        s
    }

    /// The same scene with the light's cells cut out (holes: they neither
    /// emit nor occlude), for the bounce light alone.
    pub fn without_emitter(&self) -> ExactScene {
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
}
