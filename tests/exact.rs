//! The gather against closed-form answers (`pbgi::exact`): a box room of
//! piecewise-constant cells with a small bright ceiling light (Lambert's
//! polygon formula gives the exact irradiance), the same room lit by its
//! walls alone, and an open box (occlusion is one minus the opening's form
//! factor). Receivers in the middle of walls ("mid": more than a surfel
//! spacing from the next wall) over jittered surfels, and every receiver,
//! near edges and in corners too, over surfels on a grid, each standing for
//! its own cell (over jittered ones the nearest receivers measure where the
//! surfels beside them happen to lie, which only density lowers).
//!
//! Asserted, through the 16-lane pipeline users run (the glossy lobe through
//! the scalar one, the only one that convolves it): the error at the render
//! defaults ≤ 3 %, at the finest setting ≤ 1 %; it falls as Ω → 0 and as
//! the density grows; the mean bias stays within ±1 % at every N from 8 to
//! 64. Figures: docs/lab/BENCHMARKS.md, "The gather against exact answers" (`cargo
//! run --release --example exact`).

use glam::Vec3;
use pbgi::Scheme;
use pbgi::brdf::GlossyLobe;
use pbgi::exact::{ExactScene, GatherSettings, Probe, Quantity, RoomSpec, Stats, gather, stats};
use pbgi::render::RenderOptions;

/// The render's defaults: Ω and N of irradiance (and occlusion) gathers.
fn defaults() -> (f32, usize) {
    let o = RenderOptions::default();
    (o.cut.max_solid_angle, o.microbuffer)
}

/// Mid receivers' error of `what` in `scene` (surfels `k` per cell side,
/// jittered with a fixed seed).
fn error(scene: &ExactScene, probes: &[Probe], k: usize, what: Quantity, omega: f32, n: usize) -> Stats {
    error_with(scene, probes, k, what, (omega, 0.0), n)
}

/// [`error`] at Ω and the cut's light offset weight `cut`.
fn error_with(
    scene: &ExactScene,
    probes: &[Probe],
    k: usize,
    what: Quantity,
    cut: (f32, f32),
    n: usize,
) -> Stats {
    let tree = scene.tree(k, Some(7)).expect("valid surfels");
    measure(scene, &tree, probes, what, cut, n, &format!("k {k}"))
}

/// The error of `what` over `probes` with surfels on a regular grid, `k`
/// per cell side: each surfel stands for its own square, so Lambert's
/// formula over the cells is the exact answer for the cloud itself, also
/// at a receiver nearer the next wall than the surfel spacing.
fn grid_error(scene: &ExactScene, probes: &[Probe], k: usize, what: Quantity, omega: f32, n: usize) -> Stats {
    let tree = scene.tree(k, None).expect("valid surfels");
    measure(
        scene,
        &tree,
        probes,
        what,
        (omega, 0.0),
        n,
        &format!("grid k {k}"),
    )
}

fn measure(
    scene: &ExactScene,
    tree: &pbgi::Tree,
    probes: &[Probe],
    what: Quantity,
    cut: (f32, f32),
    n: usize,
    cloud: &str,
) -> Stats {
    let (omega, light_offset) = cut;
    let exact: Vec<f64> = probes
        .iter()
        .map(|p| {
            let (e, o) = scene.exact(p.position, p.normal);
            match what {
                Quantity::Occlusion => o,
                Quantity::Glossy(lobe) => scene.glossy(p.position, p.normal, p.wo, &lobe, 500),
                Quantity::Irradiance => e,
            }
        })
        .collect();
    let v = gathered(scene, tree, probes, what, cut, n);
    let s = stats(&v, &exact);
    eprintln!(
        "{cloud}, Ω {omega}, light offset {light_offset}, N {n}: RMSE {:.3} %, bias {:+.3} %",
        100.0 * s.rel_rmse,
        100.0 * s.bias
    );
    s
}

/// `what` gathered at `probes` as the renderer's 16-lane pipeline does
/// (the scalar one for a glossy lobe), under the scene's sky.
fn gathered(
    scene: &ExactScene,
    tree: &pbgi::Tree,
    probes: &[Probe],
    what: Quantity,
    cut: (f32, f32),
    n: usize,
) -> Vec<f64> {
    let g = GatherSettings {
        max_solid_angle: cut.0,
        light_offset: cut.1,
        resolution: n,
        lanes: !matches!(what, Quantity::Glossy(_)),
        scheme: Scheme::Packet,
        sky: scene.sky as f32,
    };
    gather(tree, probes, what, &g).expect("gather").0
}

fn mid(scene: &ExactScene) -> Vec<Probe> {
    let mut p = scene.probes(2e-5);
    p.retain(|p| p.class == "mid");
    assert!(p.len() >= 20, "too few mid receivers to measure anything");
    p
}

fn light_room() -> ExactScene {
    ExactScene::room(&RoomSpec::default())
}

/// The room without its ceiling: occlusion is one minus the opening's form
/// factor.
fn open_room() -> ExactScene {
    ExactScene::room(&RoomSpec {
        open_ceiling: true,
        ..Default::default()
    })
}

#[test]
fn small_bright_light_converges_as_the_solid_angle_shrinks() {
    let scene = light_room();
    let probes = mid(&scene);
    let (omega, n) = defaults();
    let defaults = error(&scene, &probes, 8, Quantity::Irradiance, omega, n);
    assert!(
        defaults.rel_rmse <= 0.03 && defaults.bias.abs() <= 0.01,
        "defaults: {defaults:?}"
    );
    // At N 24 the error levels off at about 0.1 % below Ω 0.01: the 4×4
    // sub-samples' own discretization (where a sub-sample straddles two
    // walls), which only N lowers (next test). At N 48 that floor is a
    // third as deep, below each Ω step.
    let at = |omega| error(&scene, &probes, 8, Quantity::Irradiance, omega, 48);
    let (coarse, finer, finest) = (at(0.05), at(0.01), at(0.001));
    assert!(finest.rel_rmse <= 0.01, "finest: {finest:?}");
    assert!(
        coarse.rel_rmse > finer.rel_rmse && finer.rel_rmse > finest.rel_rmse,
        "not converging as Ω → 0: {coarse:?} {finer:?} {finest:?}"
    );
}

#[test]
fn at_the_smallest_solid_angle_the_error_falls_as_the_resolution_grows() {
    let scene = light_room();
    let probes = mid(&scene);
    // 0.15 / 0.03 / 0.01 % at N 8 / 16 / 48. In between it wobbles within
    // 0.06 % (N 12 0.06, N 24 0.06, N 32 0.04 %): where a sub-sample
    // straddles two walls, which walls' splats it holds depends on how
    // the pixels fall on the room's corners. Before small splats went
    // whole into their pixel, N 12 / 24 / 48 were 0.34 / 0.09 / 0.03 %.
    let errors: Vec<Stats> = [8, 16, 48]
        .iter()
        .map(|&n| error(&scene, &probes, 8, Quantity::Irradiance, 0.001, n))
        .collect();
    for w in errors.windows(2) {
        assert!(w[0].rel_rmse > w[1].rel_rmse, "resolution: {errors:?}");
    }
}

#[test]
fn bias_stays_within_one_percent_at_every_resolution() {
    let scene = light_room();
    let probes = mid(&scene);
    let bounce = scene.without_emitter();
    let bounce_probes = mid(&bounce);
    for n in [8, 12, 16, 32, 64] {
        for (s, p) in [(&scene, &probes), (&bounce, &bounce_probes)] {
            let e = error(s, p, 8, Quantity::Irradiance, 0.05, n);
            assert!(e.bias.abs() <= 0.01, "N {n}: {e:?}");
            assert!(e.rel_rmse <= 0.03, "N {n}: {e:?}");
        }
    }
}

#[test]
fn error_falls_as_the_density_grows() {
    let scene = light_room();
    let probes = mid(&scene);
    let errors: Vec<Stats> = [2, 4, 8]
        .iter()
        .map(|&k| error(&scene, &probes, k, Quantity::Irradiance, 0.01, 16))
        .collect();
    for w in errors.windows(2) {
        assert!(w[0].rel_rmse > w[1].rel_rmse, "density: {errors:?}");
    }
}

#[test]
fn occlusion_of_an_open_box_is_one_minus_the_form_factor_of_its_opening() {
    let scene = open_room();
    let probes = mid(&scene);
    let (omega, n) = defaults();
    let defaults = error(&scene, &probes, 8, Quantity::Occlusion, omega, n);
    let finest = error(&scene, &probes, 8, Quantity::Occlusion, 0.001, 16);
    assert!(
        defaults.rel_rmse <= 0.03 && defaults.bias.abs() <= 0.01,
        "{defaults:?}"
    );
    assert!(finest.rel_rmse <= 0.01, "{finest:?}");
}

#[test]
fn a_slab_under_the_light_hides_it_where_it_lies_in_the_pixel() {
    // Occlusion by the blocker's slab: where its edge crosses a pixel, the
    // sub-samples it covers hide what lies behind and the others do not.
    // Composed per pixel (one layer's coverage hiding the whole pixel in
    // proportion) this was 1.73 % mid-wall at Ω 0.01, N 24; now 0.14 %.
    let scene = ExactScene::room(&RoomSpec {
        blocker: true,
        ..Default::default()
    });
    let probes = mid(&scene);
    let e = error(&scene, &probes, 8, Quantity::Occlusion, 0.01, 24);
    assert!(e.rel_rmse <= 0.01 && e.bias.abs() <= 0.01, "{e:?}");
}

#[test]
fn a_light_behind_a_slab_stays_hidden_as_the_resolution_grows() {
    // Fine sub-samples resolve the gaps between the slab's splats (disks of
    // their own area do not tile it); where coverage alone decided, the
    // light behind showed through them, more as N grew: mid-wall irradiance
    // 6.0 / 7.5 / 12.7 % at N 24 / 48 / 96 (Ω 0.002). Each splat now hides
    // what lies behind over its grown disk: 5.6 / 1.8 / 1.4 %.
    let scene = ExactScene::room(&RoomSpec {
        blocker: true,
        ..Default::default()
    });
    let probes = mid(&scene);
    let errors: Vec<Stats> = [24, 48, 96]
        .iter()
        .map(|&n| error(&scene, &probes, 8, Quantity::Irradiance, 0.002, n))
        .collect();
    for w in errors.windows(2) {
        assert!(w[0].rel_rmse > w[1].rel_rmse, "N: {errors:?}");
    }
    assert!(errors[2].rel_rmse <= 0.02, "{errors:?}");
    // At a coarse Ω the light's cluster, drawn at its area centroid, is
    // hidden by the slab where the light is not (or the reverse): 11.8 %
    // at Ω 0.2, N 24; refined by its light offset (weight 4), 5.3 %.
    let plain = error_with(&scene, &probes, 8, Quantity::Irradiance, (0.2, 0.0), 24);
    let offset = error_with(&scene, &probes, 8, Quantity::Irradiance, (0.2, 4.0), 24);
    assert!(plain.rel_rmse > 2.0 * offset.rel_rmse, "{plain:?} {offset:?}");
}

#[test]
fn a_cluster_sends_its_light_from_where_it_lies_at_a_coarse_solid_angle() {
    // At Ω 0.2 one cluster holds the small bright light and the dark
    // ceiling around it. Sent from the centre of its box (or from its area
    // centroid) the light sat up to `R` from where it is: mid-wall 3.4 %
    // low (the light alone 7 %). Sent from its light centroid, 0.8 %.
    let scene = light_room();
    let e = error(&scene, &mid(&scene), 8, Quantity::Irradiance, 0.2, 8);
    assert!(e.rel_rmse <= 0.01 && e.bias.abs() <= 0.01, "{e:?}");
    // The walls' own light: a cluster on a room's edge sends each facet's
    // light from that facet's light centroid (from one point for the
    // whole cluster, 1.0 %, bias −1.0 %; from the box's centre, +1.1 %).
    let bounce = scene.without_emitter();
    let e = error(&bounce, &mid(&bounce), 8, Quantity::Irradiance, 0.1, 24);
    assert!(e.rel_rmse <= 0.005, "{e:?}");
}

#[test]
fn a_glossy_lobe_converges_where_clusters_send_their_light_from_their_surface() {
    // The lobe (roughness 0.3, towards the room's middle) reads each
    // cluster's light where the cluster is drawn, not only its sum: at Ω
    // 0.2 the small bright light's cluster shows it up to a footprint's
    // width from where it lies, 21 % mid-wall (irradiance 0.5 %). Counting
    // a cluster larger by 4 times its light centroid's offset from its area
    // centroid refines those clusters until their light is where their
    // surface is: 3.2 % at Ω 0.2. Glossy receivers gather so, and at their
    // own Ω.
    let scene = light_room();
    let probes = mid(&scene);
    let lobe = Quantity::Glossy(GlossyLobe {
        specular: Vec3::ONE,
        roughness: 0.3,
    });
    let o = RenderOptions::default();
    let (omega, k, n) = (
        o.glossy_max_solid_angle,
        o.glossy_light_offset,
        o.glossy_microbuffer,
    );
    let defaults = error_with(&scene, &probes, 8, lobe, (omega, k), n);
    assert!(
        defaults.rel_rmse <= 0.03 && defaults.bias.abs() <= 0.01,
        "defaults: {defaults:?}"
    );
    let plain = error_with(&scene, &probes, 8, lobe, (0.2, 0.0), 24);
    let offset = error_with(&scene, &probes, 8, lobe, (0.2, 4.0), 24);
    assert!(plain.rel_rmse > 4.0 * offset.rel_rmse, "{plain:?} {offset:?}");
    let errors: Vec<Stats> = [0.2, 0.05, 0.01]
        .iter()
        .map(|&omega| error_with(&scene, &probes, 8, lobe, (omega, k), 32))
        .collect();
    for w in errors.windows(2) {
        assert!(
            w[0].rel_rmse > w[1].rel_rmse,
            "not converging as Ω → 0: {errors:?}"
        );
    }
    assert!(errors[2].rel_rmse <= 0.01, "finest: {errors:?}");
}

/// Every receiver: mid-wall, 0.08 and 0.01 from an edge (closer to the next
/// wall than the surfel spacing, 0.016 at k 8), and in corners, where two
/// walls are seen edge-on. Over jittered surfels those nearest receivers
/// read where the few surfels beside them happen to lie (2.5 % over all
/// receivers at the defaults, 0.5 % mid-wall), an error of the cloud that
/// only density lowers; over surfels on a grid each surfel stands for its
/// own cell and the exact answer is the cloud's own ([`grid_error`]).
fn every(scene: &ExactScene) -> Vec<Probe> {
    let p = scene.probes(2e-5);
    assert!(p.iter().filter(|p| p.class == "corner").count() >= 20);
    p
}

#[test]
fn at_every_receiver_the_defaults_are_within_three_percent_unbiased() {
    let (omega, n) = defaults();
    let light = light_room();
    let bounce = light.without_emitter();
    let open = open_room();
    for (scene, what) in [
        (&light, Quantity::Irradiance),
        (&bounce, Quantity::Irradiance),
        (&open, Quantity::Occlusion),
    ] {
        let e = grid_error(scene, &every(scene), 8, what, omega, n);
        assert!(e.rel_rmse <= 0.03 && e.bias.abs() <= 0.01, "{what:?}: {e:?}");
    }
}

#[test]
fn at_every_receiver_the_error_falls_as_the_solid_angle_shrinks_and_the_resolution_grows() {
    let scene = light_room();
    let probes = every(&scene);
    let at = |omega, n| grid_error(&scene, &probes, 8, Quantity::Irradiance, omega, n);
    let by_omega: Vec<Stats> = [0.15, 0.05, 0.01, 0.001].iter().map(|&o| at(o, 48)).collect();
    for w in by_omega.windows(2) {
        assert!(w[0].rel_rmse > w[1].rel_rmse, "Ω: {by_omega:?}");
    }
    assert!(by_omega[3].rel_rmse <= 0.01, "finest: {by_omega:?}");
    let by_n: Vec<Stats> = [14, 24, 48].iter().map(|&n| at(0.001, n)).collect();
    for w in by_n.windows(2) {
        assert!(w[0].rel_rmse > w[1].rel_rmse, "N: {by_n:?}");
    }
}

#[test]
fn a_corner_receiver_seeing_two_walls_edge_on_converges_as_the_resolution_grows() {
    // Where it sees two walls edge-on the microbuffer's resolution bounds
    // the error (at N 48 it is 0.3 % from Ω 0.05 down, in the light room);
    // it falls with N at every Ω. (The receivers 0.01 from one edge rise
    // from N 24 to 48, 0.2–0.3 to 0.3–0.7 %: the next wall's nearest
    // surfels, a few times the receiver's distance across, drawn as disks.)
    let open = open_room();
    let light = light_room();
    for (scene, what) in [(&light, Quantity::Irradiance), (&open, Quantity::Occlusion)] {
        let mut probes = every(scene);
        probes.retain(|p| p.class == "corner");
        let errors: Vec<Stats> = [14, 24, 48]
            .iter()
            .map(|&n| grid_error(scene, &probes, 8, what, 0.01, n))
            .collect();
        for w in errors.windows(2) {
            assert!(w[0].rel_rmse > w[1].rel_rmse, "{what:?}, N: {errors:?}");
        }
        assert!(errors[2].rel_rmse <= 0.01, "{what:?}: {errors:?}");
    }
}

#[test]
fn a_surfel_beside_a_nearer_wall_is_not_lost() {
    // Leaves only, N 14: most surfels are under half a sub-sample across
    // and go whole to the sub-sample their centre falls in. Spread over
    // the 2×2 pixels around it, a surfel beside a room's corner left part
    // of itself a pixel away, where the nearer wall hid it: the open room's
    // mid-wall occlusion −0.53 %. Whole in its pixel, −0.14 % (what is
    // left: sub-samples straddling the corner, −0.03 % at N 24).
    let open = open_room();
    let e = grid_error(&open, &mid(&open), 8, Quantity::Occlusion, 0.0, 14);
    assert!(e.bias.abs() <= 0.0025, "{e:?}");
}

/// A room with openings ([`pbgi::exact::opening`]).
fn opening(name: &str) -> ExactScene {
    ExactScene::room(&pbgi::exact::opening(name).expect("a scene with openings"))
}

#[test]
fn sky_through_a_window_converges_to_the_sky_times_the_window_s_projected_solid_angle() {
    // The room black, a uniform sky: Lambert's formula over the window
    // (clipped to the receiver's horizon) times the sky's radiance, at the
    // mid-wall receivers, over surfels on a grid (the cloud is exactly the
    // walls). A single sheet, and a wall 0.075 thick with its jambs.
    // The sky is what the walls leave open, a small difference of large
    // sums: splats drawn at their far-field solid angle covered 1 % of the
    // hemisphere too much, and the sky came out 24–30 % short at the
    // defaults. Converges at N 24 (Ω 0.15 / 0.05 / 0.01 / 0.001): 7.95 /
    // 1.66 / 0.53 / 0.33 % and 8.43 / 2.22 / 0.71 / 0.75 %. From Ω 0.01 on
    // the cut is as good as N 24 resolves (the sunroom's last step is
    // noise, 0.71 against 0.75 %): it falls to Ω 0.01 and stays within 1 %.
    for name in ["window", "sunroom"] {
        let scene = opening(name).dark_inside();
        let probes = mid(&scene);
        let at = |o| grid_error(&scene, &probes, 8, Quantity::Irradiance, o, 24);
        let by_omega: Vec<Stats> = [0.15, 0.05, 0.01, 0.001].iter().map(|&o| at(o)).collect();
        for w in by_omega[..3].windows(2) {
            assert!(w[0].rel_rmse > w[1].rel_rmse, "{name}, Ω: {by_omega:?}");
        }
        for s in &by_omega[2..] {
            assert!(s.rel_rmse <= 0.01, "{name}, finest: {by_omega:?}");
        }
    }
}

#[test]
fn rooms_with_openings_converge_as_the_solid_angle_shrinks_and_the_resolution_grows() {
    // Sky through a window in a single sheet and through a thick wall
    // with a sunlit floor patch, and the closed thick-walled box under the
    // sky, at every receiver (near the window too) over surfels on a grid.
    for name in ["window", "sunroom", "shell"] {
        let scene = opening(name);
        let probes = every(&scene);
        let at = |omega, n| grid_error(&scene, &probes, 8, Quantity::Irradiance, omega, n);
        // From Ω 0.01 on the cut is as good as N 48 resolves (the window's
        // 1.089 against 1.090 % at Ω 0.001): the N sweep below goes on.
        let by_omega: Vec<Stats> = [0.15, 0.01, 0.001].iter().map(|&o| at(o, 48)).collect();
        assert!(
            by_omega[0].rel_rmse > by_omega[1].rel_rmse,
            "{name}, Ω: {by_omega:?}"
        );
        assert!(
            by_omega[2].rel_rmse <= by_omega[1].rel_rmse * 1.01,
            "{name}, Ω: {by_omega:?}"
        );
        let by_n: Vec<Stats> = [14, 24, 48, 96].iter().map(|&n| at(0.001, n)).collect();
        for w in by_n.windows(2) {
            assert!(w[0].rel_rmse > w[1].rel_rmse, "{name}, N: {by_n:?}");
        }
        assert!(by_n[3].rel_rmse <= 0.01, "{name}, finest: {by_n:?}");
    }
}

#[test]
fn a_closed_box_with_thick_walls_lets_nothing_of_its_outside_in() {
    // Walls 0.075 and 0.02 thick, the outside lit (the roof twice as
    // bright), the room itself and the sky black: nothing arrives inside,
    // at any receiver (corners too), at any Ω or N, over jittered surfels
    // or a grid. The tree once grouped a wall's inside and outside at the
    // room's edges; such a cluster, drawn as a round cone with its mean
    // normal cancelled, covered too little and showed its sunlit outside
    // (and, under a sky, the sky: mid-wall +15 % at the defaults). The sky
    // is left out here because the API's gather has no near field: from a
    // corner the next wall, seen edge-on, leaves gaps at N 14 (the
    // renderer casts rays there). Not yet exact (measured, grid and
    // jittered): at Ω 0.5 up to 43 receivers near the edges see up to
    // 0.08 (the room's own light is about 1.4), and at Ω 0.15, N 24 one of
    // the thin shell's corners 0.0008; clusters holding one wall's inside
    // and the next wall's outside (no two of their faces back to back)
    // remain there.
    for (name, omegas) in [("shell", &[0.15, 0.05][..]), ("thin-shell", &[0.05][..])] {
        let mut scene = opening(name).dark_inside();
        scene.sky = 0.0;
        let probes = every(&scene);
        for seed in [None, Some(7)] {
            let tree = scene.tree(2, seed).expect("valid surfels");
            for &omega in omegas {
                for n in [14, 24] {
                    let v = gathered(&scene, &tree, &probes, Quantity::Irradiance, (omega, 0.0), n);
                    let lit: Vec<(&str, &str, f64)> = probes
                        .iter()
                        .zip(&v)
                        .filter(|(_, e)| **e != 0.0)
                        .map(|(p, &e)| (p.face, p.class, e))
                        .collect();
                    assert!(lit.is_empty(), "{name} {seed:?} Ω {omega} N {n}: {lit:?}");
                }
            }
        }
    }
    // Lit inside as well, mid-wall at the render's defaults (grid, 4 surfels
    // per cell side): the thick-walled room with the window, and the closed one.
    let (omega, n) = defaults();
    for name in ["sunroom", "shell"] {
        let scene = opening(name);
        let e = grid_error(&scene, &mid(&scene), 4, Quantity::Irradiance, omega, n);
        assert!(e.rel_rmse <= 0.015 && e.bias.abs() <= 0.015, "{name}: {e:?}");
    }
}

#[test]
fn a_window_s_sky_does_not_depend_on_the_microbuffer_s_resolution() {
    // The sky a receiver sees is what its cut leaves open, a small
    // difference of large sums: each splat must add its own projected
    // solid angle, at any N. A cone filling some pixels kept what they
    // could not take when scaled to its area (up to 5 % of it lost, more at
    // N 24 than at 14 or 48), and splats were drawn at their far-field
    // solid angle, 2–5 % over their cells. Room black, mid receivers, grid
    // k 8, Ω 0.05: the window's sky was −12.7 % at N 14 and −7.0 % at
    // N 24 (k 4); now 1.4 / 1.3 / 1.3 % (RMSE) at N 14 / 24 / 48.
    let scene = opening("window").dark_inside();
    let probes = mid(&scene);
    for n in [14, 24, 48] {
        let e = grid_error(&scene, &probes, 8, Quantity::Irradiance, 0.05, n);
        assert!(e.rel_rmse <= 0.02 && e.bias.abs() <= 0.02, "N {n}: {e:?}");
    }
}
