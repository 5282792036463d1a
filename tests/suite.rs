//! The integration tests, one binary. Each file of `tests/` is a module
//! here, not a test binary of its own: each binary links the whole crate
//! (with fat LTO under `--release`, about 30 s apiece), so one binary
//! keeps the README's test command's links to a few. A file's tests are
//! named after it:
//! `cargo test --profile quick --test suite -- render_gathers::` runs `tests/render_gathers.rs`.

// The tests use the lab (synthetic clouds, exact references, the report)
// and the CLI: a build without them fails here rather than running none.
#[cfg(not(feature = "cli"))]
compile_error!(
    "the tests need the `cli` feature (the default): run `cargo test` without --no-default-features"
);

mod common;

mod bad_input;
mod cache;
mod camera_path;
mod camera_samples;
mod cli;
mod cut_equivalence;
#[cfg(feature = "denoise")]
mod denoise;
mod exact;
mod gather;
mod gltf;
mod guides;
mod hiding;
mod inputs;
mod readme;
mod reference;
mod render;
mod render_gathers;
mod report;
mod scene_loaders;
mod scenes;
mod shading_analytic;
mod sky_rays;
mod stability;
mod surfel_budget;
mod textures;
mod tiles;
mod tree_build;
mod tree_file;
