//! What a gather sees of a scene (surfels, probes) and the exact answers
//! it is measured against.

use glam::{DVec3, Vec3};

use super::{ExactScene, Part, Probe, WINDOW};
use crate::brdf::GlossyLobe;
use crate::microbuffer::Sight;
use crate::polygon::{clip, projected_solid_angle};
use crate::rng::Rng;
use crate::{Error, PointCloud, Surfel, Tree};

impl ExactScene {
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

    /// Whether the ray from `p` along unit `d` leaves the scene (the sky
    /// shows there).
    pub fn escapes(&self, p: Vec3, d: Vec3) -> bool {
        self.hit(p.as_dvec3(), d.as_dvec3().normalize()).is_none()
    }

    /// What the ray from `p` along unit `d` meets first: the sky, or a face
    /// and the cosine there.
    pub fn sight(&self, p: Vec3, d: Vec3) -> Sight {
        let d = d.as_dvec3().normalize();
        self.hit(p.as_dvec3(), d)
            .map_or(Sight::Sky, |(k, _, _)| Sight::Surface {
                cos: self.faces[k].normal().dot(d).abs() as f32,
            })
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
