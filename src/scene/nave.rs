//! `nave`: a procedural church interior standing in for the paper's Sibenik
//! cathedral, which no package registry ships. It is not Sibenik: it is a
//! generic three-aisled Gothic nave built here from boxes, extruded pointed
//! arches and a pointed barrel vault.
//!
//! Seven bays, 3.5 units long: a nave 1.2 wide between two rows of piers
//! (12-sided, smooth normals, plinth and capital) carrying pointed arcades;
//! side aisles 0.44 wide under flat ceilings; a clerestory with one pointed
//! window *opening* per bay and side; a pointed barrel vault with transverse
//! ribs; a chequered floor. Light: a sun from the right through the
//! clerestory openings (pools of light on the left side), a rose window over
//! the entrance and a lancet window in the east wall (emissive panels), and a
//! glazed lancet in each aisle bay (dimmer emissive panels). Every surface
//! faces the interior; 4,320 triangles; 320×240.

use glam::Vec3;

use super::{Camera, FovAxis, Light, Material, Mesh, Scene};

/// Bays along the nave.
const BAYS: usize = 7;
/// Bay length (z).
const BAY: f32 = 0.5;
/// Nave length.
const LENGTH: f32 = BAYS as f32 * BAY;
/// Pier axis, |x|.
const ARCADE_X: f32 = 0.6;
/// Arcade wall thickness.
const WALL: f32 = 0.12;
/// Outer aisle wall, |x|.
const AISLE_X: f32 = 1.1;
/// Pier radius.
const PIER_R: f32 = 0.07;
/// Arcade springing height (top of the capitals).
const SPRING: f32 = 0.7;
/// Aisle ceiling height.
const AISLE_TOP: f32 = 1.2;
/// Vault springing height (top of the clerestory wall).
const VAULT_SPRING: f32 = 2.0;
/// Vault rise as a fraction of an equilateral pointed arch.
const VAULT_RISE: f32 = 0.6;
/// Clerestory window: half width, sill, springing.
const WIN_HALF: f32 = 0.15;
const WIN_SILL: f32 = 1.3;
const WIN_SPRING: f32 = 1.7;

const STONE: usize = 0;
const FLOOR_LIGHT: usize = 1;
const FLOOR_DARK: usize = 2;
const PLASTER: usize = 3;
const GLASS: usize = 4;

/// Height of an equilateral pointed arch of half span `s` at offset `u` from its axis.
fn pointed(u: f32, s: f32) -> f32 {
    let u = u.abs().min(s);
    ((2.0 * s) * (2.0 * s) - (u + s) * (u + s)).max(0.0).sqrt()
}

/// `n + 1` offsets spanning `[-s, s]`.
fn samples(s: f32, n: usize) -> Vec<f32> {
    (0..=n).map(|i| -s + 2.0 * s * i as f32 / n as f32).collect()
}

/// Sorted union of offset lists, near-duplicates merged.
fn merge(mut a: Vec<f32>, b: &[f32]) -> Vec<f32> {
    a.extend_from_slice(b);
    a.sort_by(f32::total_cmp);
    a.dedup_by(|x, y| (*x - *y).abs() < 1e-5);
    a
}

struct Builder {
    meshes: Vec<Mesh>,
}

impl Builder {
    fn mesh(&mut self, name: &str, material: usize, emission: Option<Vec3>) -> usize {
        self.meshes.push(Mesh {
            name: name.to_string(),
            material,
            emission,
            ..Mesh::default()
        });
        self.meshes.len() - 1
    }

    /// A planar quad (or a triangle, when two corners coincide) whose front
    /// faces along `facing` (only its sign relative to the quad matters).
    fn quad(&mut self, mesh: usize, v: [Vec3; 4], facing: Vec3) {
        let n = (v[2] - v[0]).cross(v[3] - v[1]);
        let v = if n.dot(facing) < 0.0 {
            [v[0], v[3], v[2], v[1]]
        } else {
            v
        };
        let m = &mut self.meshes[mesh];
        for t in [[v[0], v[1], v[2]], [v[0], v[2], v[3]]] {
            if (t[1] - t[0]).cross(t[2] - t[0]).length_squared() < 1e-14 {
                continue;
            }
            let base = m.positions.len() as u32;
            m.positions.extend_from_slice(&t);
            m.triangles.push([base, base + 1, base + 2]);
        }
    }

    /// An axis-aligned box without its bottom face, faces outward.
    fn block(&mut self, mesh: usize, lo: Vec3, hi: Vec3) {
        let c = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        let (a, b) = (lo, hi);
        self.quad(
            mesh,
            [
                c(a.x, b.y, a.z),
                c(b.x, b.y, a.z),
                c(b.x, b.y, b.z),
                c(a.x, b.y, b.z),
            ],
            Vec3::Y,
        );
        self.quad(
            mesh,
            [
                c(a.x, a.y, a.z),
                c(a.x, b.y, a.z),
                c(a.x, b.y, b.z),
                c(a.x, a.y, b.z),
            ],
            -Vec3::X,
        );
        self.quad(
            mesh,
            [
                c(b.x, a.y, a.z),
                c(b.x, b.y, a.z),
                c(b.x, b.y, b.z),
                c(b.x, a.y, b.z),
            ],
            Vec3::X,
        );
        self.quad(
            mesh,
            [
                c(a.x, a.y, a.z),
                c(b.x, a.y, a.z),
                c(b.x, b.y, a.z),
                c(a.x, b.y, a.z),
            ],
            -Vec3::Z,
        );
        self.quad(
            mesh,
            [
                c(a.x, a.y, b.z),
                c(b.x, a.y, b.z),
                c(b.x, b.y, b.z),
                c(a.x, b.y, b.z),
            ],
            Vec3::Z,
        );
    }

    /// A pier: a 12-sided shaft with smooth normals on a plinth, under a capital.
    fn pier(&mut self, x: f32, z: f32) {
        const SIDES: usize = 12;
        let (plinth, capital) = (0.05, SPRING - 0.05);
        let shaft = self.mesh(&format!("pier {x:+.1} {z:.1}"), STONE, None);
        let m = &mut self.meshes[shaft];
        let mut normals = Vec::new();
        for i in 0..=SIDES {
            let a = std::f32::consts::TAU * i as f32 / SIDES as f32;
            let n = Vec3::new(a.cos(), 0.0, a.sin());
            for y in [plinth, capital] {
                m.positions.push(Vec3::new(x, y, z) + n * PIER_R);
                normals.push(n);
            }
        }
        for i in 0..SIDES as u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            // Outward: (b − a) × (c − a) must point along the radial normal.
            m.triangles.push([a, b, d]);
            m.triangles.push([a, d, c]);
        }
        m.normals = Some(normals);
        let blocks = self.mesh(&format!("pier {x:+.1} {z:.1} base and capital"), STONE, None);
        self.block(
            blocks,
            Vec3::new(x - 0.1, 0.0, z - 0.1),
            Vec3::new(x + 0.1, plinth, z + 0.1),
        );
        self.block(
            blocks,
            Vec3::new(x - 0.1, capital, z - 0.1),
            Vec3::new(x + 0.1, SPRING, z + 0.1),
        );
    }
}

/// A solid span of a wall column: bottom and top heights at both ends.
type Span = (f32, f32, f32, f32);

/// Emits a vertical wall in the plane `x = x` as columns between z
/// breakpoints, each with the solid spans given.
fn wall_x(b: &mut Builder, mesh: usize, x: f32, facing: Vec3, columns: &[(f32, f32, Vec<Span>)]) {
    for (z0, z1, spans) in columns {
        for &(y0a, y0b, y1a, y1b) in spans {
            if y1a - y0a <= 1e-6 && y1b - y0b <= 1e-6 {
                continue;
            }
            b.quad(
                mesh,
                [
                    Vec3::new(x, y0a, *z0),
                    Vec3::new(x, y0b, *z1),
                    Vec3::new(x, y1b, *z1),
                    Vec3::new(x, y1a, *z0),
                ],
                facing,
            );
        }
    }
}

/// As [`wall_x`] in the plane `z = z`, columns between x breakpoints.
fn wall_z(b: &mut Builder, mesh: usize, z: f32, facing: Vec3, columns: &[(f32, f32, Vec<Span>)]) {
    for (x0, x1, spans) in columns {
        for &(y0a, y0b, y1a, y1b) in spans {
            if y1a - y0a <= 1e-6 && y1b - y0b <= 1e-6 {
                continue;
            }
            b.quad(
                mesh,
                [
                    Vec3::new(*x0, y0a, z),
                    Vec3::new(*x1, y0b, z),
                    Vec3::new(*x1, y1b, z),
                    Vec3::new(*x0, y1a, z),
                ],
                facing,
            );
        }
    }
}

/// Vault height at `x` (|x| ≤ the vault's half span).
fn vault(x: f32) -> f32 {
    let s = ARCADE_X - WALL / 2.0;
    VAULT_SPRING + VAULT_RISE * pointed(x, s)
}

/// The procedural nave (see the module documentation).
pub fn nave() -> Scene {
    let materials = vec![
        Material::diffuse("stone", Vec3::new(0.62, 0.57, 0.49)),
        Material::diffuse("floor-light", Vec3::new(0.7, 0.68, 0.63)),
        Material::diffuse("floor-dark", Vec3::new(0.28, 0.25, 0.22)),
        Material::diffuse("plaster", Vec3::new(0.75, 0.72, 0.66)),
        Material::diffuse("glass", Vec3::new(0.05, 0.05, 0.05)),
    ];
    let mut b = Builder { meshes: Vec::new() };
    let arch_s = (BAY - 2.0 * PIER_R) / 2.0; // half span of an arcade arch
    let arch_u = samples(arch_s, 10);
    let win_u = samples(WIN_HALF, 6);

    // Floor: chequered tiles 0.275 × 0.25.
    let (light, dark) = (
        b.mesh("floor light tiles", FLOOR_LIGHT, None),
        b.mesh("floor dark tiles", FLOOR_DARK, None),
    );
    let (nx, nz) = (8, 14);
    for i in 0..nx {
        for k in 0..nz {
            let x0 = -AISLE_X + 2.0 * AISLE_X * i as f32 / nx as f32;
            let x1 = -AISLE_X + 2.0 * AISLE_X * (i + 1) as f32 / nx as f32;
            let z0 = -LENGTH * k as f32 / nz as f32;
            let z1 = -LENGTH * (k + 1) as f32 / nz as f32;
            let m = if (i + k) % 2 == 0 { light } else { dark };
            b.quad(
                m,
                [
                    Vec3::new(x0, 0.0, z0),
                    Vec3::new(x1, 0.0, z0),
                    Vec3::new(x1, 0.0, z1),
                    Vec3::new(x0, 0.0, z1),
                ],
                Vec3::Y,
            );
        }
    }

    // Piers.
    for side in [-1.0f32, 1.0] {
        for j in 1..BAYS {
            b.pier(side * ARCADE_X, -(j as f32) * BAY);
        }
    }

    // Arcade walls: nave face (with the clerestory windows), aisle face,
    // arch soffits, window reveals.
    for side in [-1.0f32, 1.0] {
        let name = if side > 0.0 { "right" } else { "left" };
        let walls = b.mesh(&format!("{name} arcade and clerestory"), STONE, None);
        let x_nave = side * (ARCADE_X - WALL / 2.0);
        let x_aisle = side * (ARCADE_X + WALL / 2.0);
        let mut nave_cols = Vec::new();
        let mut aisle_cols = Vec::new();
        for j in 0..BAYS {
            let zc = -(j as f32 + 0.5) * BAY; // bay centre
            // Solid above the pier (or end wall) before this bay's arch.
            let (za, zb) = (-(j as f32) * BAY, -(j as f32) * BAY - PIER_R);
            let pier_top = if j == 0 { 0.0 } else { SPRING };
            nave_cols.push((za, zb, vec![(pier_top, pier_top, VAULT_SPRING, VAULT_SPRING)]));
            aisle_cols.push((za, zb, vec![(pier_top, pier_top, AISLE_TOP, AISLE_TOP)]));
            // Under the arch: the arch's intrados from below, the window from the sides.
            let us = merge(arch_u.clone(), &win_u);
            for w in us.windows(2) {
                let (u0, u1) = (w[0], w[1]);
                let (y0a, y0b) = (SPRING + pointed(u0, arch_s), SPRING + pointed(u1, arch_s));
                // z decreases along the nave: offset u maps to zc − u.
                let (z0, z1) = (zc - u0, zc - u1);
                aisle_cols.push((z0, z1, vec![(y0a, y0b, AISLE_TOP, AISLE_TOP)]));
                let in_window = u0 >= -WIN_HALF - 1e-5 && u1 <= WIN_HALF + 1e-5;
                let spans = if in_window {
                    let (ta, tb) = (
                        WIN_SPRING + pointed(u0, WIN_HALF),
                        WIN_SPRING + pointed(u1, WIN_HALF),
                    );
                    vec![
                        (y0a, y0b, WIN_SILL, WIN_SILL),
                        (ta, tb, VAULT_SPRING, VAULT_SPRING),
                    ]
                } else {
                    vec![(y0a, y0b, VAULT_SPRING, VAULT_SPRING)]
                };
                nave_cols.push((z0, z1, spans));
                // Soffit of the arch, facing its opening.
                let centre = Vec3::new(0.0, SPRING, zc);
                let mid = Vec3::new(0.0, 0.5 * (y0a + y0b), 0.5 * (z0 + z1));
                b.quad(
                    walls,
                    [
                        Vec3::new(x_nave, y0a, z0),
                        Vec3::new(x_nave, y0b, z1),
                        Vec3::new(x_aisle, y0b, z1),
                        Vec3::new(x_aisle, y0a, z0),
                    ],
                    centre - mid,
                );
                // Window reveals: sill and head.
                if in_window {
                    b.quad(
                        walls,
                        [
                            Vec3::new(x_nave, WIN_SILL, z0),
                            Vec3::new(x_nave, WIN_SILL, z1),
                            Vec3::new(x_aisle, WIN_SILL, z1),
                            Vec3::new(x_aisle, WIN_SILL, z0),
                        ],
                        Vec3::Y,
                    );
                    let (ta, tb) = (
                        WIN_SPRING + pointed(u0, WIN_HALF),
                        WIN_SPRING + pointed(u1, WIN_HALF),
                    );
                    let centre = Vec3::new(0.0, WIN_SPRING, zc);
                    let mid = Vec3::new(0.0, 0.5 * (ta + tb), 0.5 * (z0 + z1));
                    b.quad(
                        walls,
                        [
                            Vec3::new(x_nave, ta, z0),
                            Vec3::new(x_nave, tb, z1),
                            Vec3::new(x_aisle, tb, z1),
                            Vec3::new(x_aisle, ta, z0),
                        ],
                        centre - mid,
                    );
                }
            }
            // Window jambs.
            for (z, facing) in [(zc + WIN_HALF, -Vec3::Z), (zc - WIN_HALF, Vec3::Z)] {
                b.quad(
                    walls,
                    [
                        Vec3::new(x_nave, WIN_SILL, z),
                        Vec3::new(x_aisle, WIN_SILL, z),
                        Vec3::new(x_aisle, WIN_SPRING, z),
                        Vec3::new(x_nave, WIN_SPRING, z),
                    ],
                    facing,
                );
            }
            // Solid above the next pier (or the east wall).
            let (za, zb) = (-(j as f32 + 1.0) * BAY + PIER_R, -(j as f32 + 1.0) * BAY);
            let pier_top = if j + 1 == BAYS { 0.0 } else { SPRING };
            nave_cols.push((za, zb, vec![(pier_top, pier_top, VAULT_SPRING, VAULT_SPRING)]));
            aisle_cols.push((za, zb, vec![(pier_top, pier_top, AISLE_TOP, AISLE_TOP)]));
        }
        wall_x(&mut b, walls, x_nave, Vec3::X * -side, &nave_cols);
        wall_x(&mut b, walls, x_aisle, Vec3::X * side, &aisle_cols);

        // Aisle ceiling and outer wall with a glazed lancet per bay.
        let aisle = b.mesh(&format!("{name} aisle"), PLASTER, None);
        b.quad(
            aisle,
            [
                Vec3::new(x_aisle, AISLE_TOP, 0.0),
                Vec3::new(side * AISLE_X, AISLE_TOP, 0.0),
                Vec3::new(side * AISLE_X, AISLE_TOP, -LENGTH),
                Vec3::new(x_aisle, AISLE_TOP, -LENGTH),
            ],
            -Vec3::Y,
        );
        wall_x(
            &mut b,
            aisle,
            side * AISLE_X,
            Vec3::X * -side,
            &[(0.0, -LENGTH, vec![(0.0, 0.0, AISLE_TOP, AISLE_TOP)])],
        );
        let glass = b.mesh(
            &format!("{name} aisle windows"),
            GLASS,
            Some(Vec3::new(1.0, 1.15, 1.4)),
        );
        let x = side * (AISLE_X - 0.002);
        for j in 0..BAYS {
            let zc = -(j as f32 + 0.5) * BAY;
            let (half, sill, spring) = (0.09, 0.35, 0.75);
            let us = samples(half, 6);
            for w in us.windows(2) {
                let (u0, u1) = (w[0], w[1]);
                b.quad(
                    glass,
                    [
                        Vec3::new(x, sill, zc - u0),
                        Vec3::new(x, sill, zc - u1),
                        Vec3::new(x, spring + pointed(u1, half), zc - u1),
                        Vec3::new(x, spring + pointed(u0, half), zc - u0),
                    ],
                    Vec3::X * -side,
                );
            }
        }
    }

    // Vault with transverse ribs.
    let vault_mesh = b.mesh("vault", PLASTER, None);
    let s = ARCADE_X - WALL / 2.0;
    let xs = samples(s, 12);
    for w in xs.windows(2) {
        let (x0, x1) = (w[0], w[1]);
        let mid = Vec3::new(0.5 * (x0 + x1), 0.5 * (vault(x0) + vault(x1)), 0.0);
        let inward = Vec3::new(0.0, VAULT_SPRING, 0.0) - mid;
        for j in 0..BAYS {
            let (z0, z1) = (-(j as f32) * BAY, -(j as f32 + 1.0) * BAY);
            b.quad(
                vault_mesh,
                [
                    Vec3::new(x0, vault(x0), z0),
                    Vec3::new(x1, vault(x1), z0),
                    Vec3::new(x1, vault(x1), z1),
                    Vec3::new(x0, vault(x0), z1),
                ],
                inward,
            );
        }
    }
    let ribs = b.mesh("vault ribs", STONE, None);
    let depth = 0.04;
    for j in 1..BAYS {
        let zc = -(j as f32) * BAY;
        let (za, zb) = (zc + 0.03, zc - 0.03);
        for w in xs.windows(2) {
            let (x0, x1) = (w[0], w[1]);
            // Inward offset along the profile normal, approximated towards the axis below.
            let axis = Vec3::new(0.0, VAULT_SPRING, 0.0);
            let p0 = Vec3::new(x0, vault(x0), 0.0);
            let p1 = Vec3::new(x1, vault(x1), 0.0);
            let q0 = p0 + (axis - p0).normalize_or_zero() * depth;
            let q1 = p1 + (axis - p1).normalize_or_zero() * depth;
            let at = |p: Vec3, z: f32| Vec3::new(p.x, p.y, z);
            let inward = axis - 0.5 * (p0 + p1);
            b.quad(ribs, [at(q0, za), at(q1, za), at(q1, zb), at(q0, zb)], inward);
            b.quad(ribs, [at(p0, za), at(p1, za), at(q1, za), at(q0, za)], Vec3::Z);
            b.quad(ribs, [at(p0, zb), at(p1, zb), at(q1, zb), at(q0, zb)], -Vec3::Z);
        }
    }

    // End walls: the top follows the vault, the arcade wall, the aisle ceiling.
    let mut xb = merge(
        xs.clone(),
        &[-AISLE_X, -ARCADE_X - WALL / 2.0, ARCADE_X + WALL / 2.0, AISLE_X],
    );
    xb.retain(|x| x.abs() <= AISLE_X + 1e-6);
    let columns: Vec<(f32, f32, Vec<Span>)> = xb
        .windows(2)
        .map(|w| {
            let (x0, x1) = (w[0], w[1]);
            let xm = 0.5 * (x0 + x1);
            let (t0, t1) = if xm.abs() < s {
                (vault(x0), vault(x1))
            } else if xm.abs() < ARCADE_X + WALL / 2.0 {
                (VAULT_SPRING, VAULT_SPRING)
            } else {
                (AISLE_TOP, AISLE_TOP)
            };
            (x0, x1, vec![(0.0, 0.0, t0, t1)])
        })
        .collect();
    let ends = b.mesh("end walls", STONE, None);
    wall_z(&mut b, ends, 0.0, -Vec3::Z, &columns);
    wall_z(&mut b, ends, -LENGTH, Vec3::Z, &columns);

    // East lancet (visible down the nave) and west rose window (behind the camera).
    let east = b.mesh("east window", GLASS, Some(Vec3::new(3.5, 3.0, 2.2)));
    let (half, sill, spring) = (0.2, 0.9, 1.75);
    let us = samples(half, 8);
    let z = -LENGTH + 0.002;
    for w in us.windows(2) {
        let (u0, u1) = (w[0], w[1]);
        b.quad(
            east,
            [
                Vec3::new(u0, sill, z),
                Vec3::new(u1, sill, z),
                Vec3::new(u1, spring + pointed(u1, half), z),
                Vec3::new(u0, spring + pointed(u0, half), z),
            ],
            Vec3::Z,
        );
    }
    let rose = b.mesh("rose window", GLASS, Some(Vec3::new(4.0, 3.6, 3.0)));
    let (centre, radius) = (Vec3::new(0.0, 1.85, -0.002), 0.3);
    for i in 0..24 {
        let a0 = std::f32::consts::TAU * i as f32 / 24.0;
        let a1 = std::f32::consts::TAU * (i + 1) as f32 / 24.0;
        let p = |a: f32| centre + Vec3::new(a.cos(), a.sin(), 0.0) * radius;
        b.quad(rose, [centre, p(a0), p(a1), p(a1)], -Vec3::Z);
    }

    Scene {
        name: "nave".into(),
        meshes: b.meshes,
        materials,
        lights: vec![Light::Directional {
            direction: Vec3::new(-0.35, -0.85, -0.4).normalize(),
            irradiance: Vec3::new(9.0, 8.2, 6.8),
        }],
        environment: None,
        camera: Camera {
            origin: Vec3::new(0.0, 0.55, -0.2),
            target: Vec3::new(0.0, 0.95, -LENGTH),
            up: Vec3::Y,
            fov_degrees: 65.0,
            fov_axis: FovAxis::X,
            width: 320,
            height: 240,
        },
        warnings: Vec::new(),
        file_settings: Default::default(),
    }
}
