//! Mesh primitives of the Mitsuba shapes that are not files (`rectangle`,
//! `cube`, `sphere`), in their canonical frames.

use glam::{Vec2, Vec3};

use super::Mesh;

/// Mitsuba's `rectangle`: [−1, 1]² in z = 0, facing +z, with its texture
/// coordinates `((x + 1)/2, (y + 1)/2)` (so, `v` growing down the image,
/// a bitmap shows upside down, as it does in Mitsuba).
pub fn quad_mesh() -> Mesh {
    Mesh {
        positions: vec![
            Vec3::new(-1.0, -1.0, 0.0),
            Vec3::new(1.0, -1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(-1.0, 1.0, 0.0),
        ],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        uvs: vec![vec![
            Vec2::new(0.0, 0.0),
            Vec2::new(1.0, 0.0),
            Vec2::new(1.0, 1.0),
            Vec2::new(0.0, 1.0),
        ]],
        ..Mesh::default()
    }
}

/// Mitsuba's `cube`: [−1, 1]³, faces outward.
pub fn cube_mesh() -> Mesh {
    let mut mesh = Mesh::default();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let n = Vec3::AXES[axis] * sign;
            let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
            let base = mesh.positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                mesh.positions.push(n + u * a + v * b);
            }
            // Counter-clockwise seen from outside.
            if sign > 0.0 {
                mesh.triangles
                    .extend([[base, base + 1, base + 2], [base, base + 2, base + 3]]);
            } else {
                mesh.triangles
                    .extend([[base, base + 2, base + 1], [base, base + 3, base + 2]]);
            }
        }
    }
    mesh
}

/// A UV sphere, outward, with smooth normals.
pub fn sphere_mesh(center: Vec3, radius: f32) -> Mesh {
    let (nu, nv) = (64u32, 32u32);
    let mut mesh = Mesh::default();
    let mut normals = Vec::new();
    for j in 0..=nv {
        let theta = std::f32::consts::PI * j as f32 / nv as f32;
        for i in 0..=nu {
            let phi = std::f32::consts::TAU * i as f32 / nu as f32;
            let n = Vec3::new(theta.sin() * phi.cos(), theta.sin() * phi.sin(), theta.cos());
            mesh.positions.push(center + n * radius);
            normals.push(n);
        }
    }
    let row = nu + 1;
    for j in 0..nv {
        for i in 0..nu {
            let (a, b, c, d) = (
                j * row + i,
                j * row + i + 1,
                (j + 1) * row + i,
                (j + 1) * row + i + 1,
            );
            if j > 0 {
                mesh.triangles.push([a, c, b]);
            }
            if j + 1 < nv {
                mesh.triangles.push([b, c, d]);
            }
        }
    }
    mesh.normals = Some(normals);
    mesh
}
