//! The surfel budget: about N surfels whatever the scene's units (a model in
//! millimetres gets as many as in metres); `--density` overrides it, giving
//! both is an error, and the summary line says which was used.

use std::path::PathBuf;

use crate::common;

use pbgi::render::{RenderOptions, render};
use pbgi::scene::builtin::cornell_box;
use pbgi::scene::{Light, Scene};

/// The scene scaled by `k` about the origin: geometry, camera and lights.
fn scaled(mut s: Scene, k: f32) -> Scene {
    for m in &mut s.meshes {
        m.positions.iter_mut().for_each(|p| *p *= k);
    }
    s.camera.origin *= k;
    s.camera.target *= k;
    for l in &mut s.lights {
        if let Light::Point { position, .. } = l {
            *position *= k;
        }
    }
    s
}

/// Surfels the render made for `scene` (a 4×4 image: the bake is what counts).
fn surfels(scene: &Scene, opts: &RenderOptions) -> usize {
    let mut s = scene.clone();
    s.camera.width = 4;
    s.camera.height = 4;
    render(&s, &RenderOptions { spp: 1, ..*opts }, &|_, _| {})
        .unwrap()
        .surfels
}

#[test]
fn the_budget_holds_in_any_units() {
    let budget = 8000;
    let opts = RenderOptions {
        surfel_budget: Some(budget),
        ..RenderOptions::default()
    };
    let metres = cornell_box();
    for k in [1.0, 1000.0, 0.001] {
        let n = surfels(&scaled(metres.clone(), k), &opts);
        let off = n as f64 / budget as f64 - 1.0;
        assert!(
            off.abs() < 0.03,
            "scale {k}: {n} surfels for a budget of {budget}"
        );
    }
    // A density is per unit area: millimetres multiply it by 10⁶ (capped
    // by the surfel limit, an error), metres keep it.
    let density = RenderOptions {
        density: 300.0,
        ..RenderOptions::default()
    };
    let n = surfels(&metres, &density);
    assert!(
        (n as f64 / (300.0 * metres.surface_area()) - 1.0).abs() < 0.05,
        "{n}"
    );
    let mm = scaled(metres, 1000.0);
    let mut tiny = mm.clone();
    tiny.camera.width = 4;
    tiny.camera.height = 4;
    assert!(
        render(&tiny, &density, &|_, _| {}).is_err(),
        "8·10⁹ surfels refused"
    );
    let zero = RenderOptions {
        surfel_budget: Some(0),
        ..RenderOptions::default()
    };
    let e = render(&tiny, &zero, &|_, _| {}).unwrap_err().to_string();
    assert!(e.contains("surfels"), "{e}");
}

#[test]
fn the_cli_uses_a_budget_for_files_and_says_so() {
    let dir =
        std::path::Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("pbgi-budget-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // A quad 2 km on a side, in millimetres: a density would ask for 10¹³ surfels.
    let quad = "OFF\n4 2 0\n-1e6 0 -1e6\n1e6 0 -1e6\n1e6 0 1e6\n-1e6 0 1e6\n3 0 2 1\n3 0 3 2\n";
    let file = dir.join("quad.off");
    std::fs::write(&file, quad).unwrap();
    let out: PathBuf = dir.join("quad.png");
    let run = |extra: &[&str]| {
        let o = common::pbgi_command()
            .args(["render", "--spp", "1", "-o"])
            .arg(&out)
            .arg(&file)
            .args(extra)
            .output()
            .unwrap();
        (
            o.status.success(),
            String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr),
        )
    };
    let (ok, text) = run(&["--surfels", "3000"]);
    assert!(ok, "{text}");
    let line = text
        .lines()
        .find(|l| l.contains(" surfels ("))
        .unwrap_or_else(|| panic!("{text}"));
    let n: f64 = line.split_whitespace().next().unwrap().parse().unwrap();
    assert!(
        line.contains("(budget 3000)") && (n / 3000.0 - 1.0).abs() < 0.03,
        "{line}"
    );
    let (ok, text) = run(&["--density", "1e-9"]);
    assert!(ok && text.contains(" surfels (density 0.000000001)"), "{text}");
    let (ok, text) = run(&["--density", "1", "--surfels", "10"]);
    assert!(!ok && text.contains("cannot be used with"), "{text}");
}

#[test]
fn a_file_gets_the_default_budget() {
    let dir = std::path::Path::new(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("pbgi-budget-default-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("small.off");
    // Tiny: 1 mm on a side in metres, 10⁻⁶ m²: density 2000 would make 2 surfels.
    std::fs::write(&file, "OFF\n3 1 0\n0 0 0\n0.001 0 0\n0 0.001 0\n3 0 1 2\n").unwrap();
    let o = common::pbgi_command()
        .args(["render", "--spp", "1", "-o"])
        .arg(dir.join("small.png"))
        .arg(&file)
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{text}{}", String::from_utf8_lossy(&o.stderr));
    let want = format!(" surfels (budget {})", pbgi::render::DEFAULT_SURFEL_BUDGET);
    assert!(text.contains(&want), "{text}");
}
