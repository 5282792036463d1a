//! The integration tests, one binary. Each file of `tests/` is a module
//! here, not a test binary of its own: the release profile links every
//! binary with fat LTO and one codegen unit, about 30 s apiece on this
//! project, so nineteen binaries cost the README's test command about ten
//! CPU-minutes of linking (five on two cores). A file's tests are named after it:
//! `cargo test --release --test suite -- gathers::` runs `tests/gathers.rs`.

mod common;

mod bad_input;
mod cache;
mod camera_path;
mod cli;
mod cut_equivalence;
mod exact;
mod gather;
mod gathers;
mod gltf;
mod hiding;
mod inputs;
mod reference;
mod render;
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
