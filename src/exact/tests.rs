use super::*;
use crate::brdf::GlossyLobe;

#[test]
fn a_closed_room_occludes_everything_and_an_open_one_the_sky_exactly() {
    let closed = ExactScene::room(&RoomSpec::default());
    let open = ExactScene::room(&RoomSpec {
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
        let s = ExactScene::room(&opening(name).expect("a scene"));
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
            let dark = ExactScene {
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
        let lit = ExactScene::room(&opening(name).expect("a scene"));
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
                (0.0..0.8 * 3.0 * 1.3 * std::f64::consts::PI).contains(&e),
                "{name} {p:?}: {e}"
            );
        }
    }
}

#[test]
fn lambert_matches_quadrature_with_and_without_the_blocker() {
    for blocker in [false, true] {
        let s = ExactScene::room(&RoomSpec {
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
