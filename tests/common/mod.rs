//! Shared by the property tests: random and adversarial clouds, receivers and
//! thresholds (quickcheck `Arbitrary` types that shrink), the case count from
//! `PBGI_QC_TESTS`, and checkers that are independent of the crate's own
//! (`Cut::check`), so a bug there cannot hide a bug in the kernels.
//!
//! Every case is generated from a few parameters (shape, size, seed), so a
//! failing case prints as a short, reproducible line, and shrinks by making
//! the cloud and the receiver set smaller (a cloud of `n` surfels is a prefix
//! of the cloud of `n + 1` with the same seed).
#![allow(dead_code)]

use std::fmt;

use glam::{DVec3, Vec3};
use pbgi::{
    Cut, CutOptions, CutRecorder, CutSink, Isa, NodeId, NodeView, Receiver, Scheme, SplatCounter, Surfel,
    Traversal, Tree,
};
use quickcheck::{Arbitrary, Gen, QuickCheck, Testable};

/// Passing cases per property: `PBGI_QC_TESTS`, default 200 (the CI's
/// emulated AArch64 stage sets 10).
pub fn cases() -> u64 {
    std::env::var("PBGI_QC_TESTS")
        .ok()
        .and_then(|s| s.trim().parse().ok())
        .unwrap_or(200)
}

/// True when the case count was turned down (emulation): fixed tests shrink too.
pub fn reduced() -> bool {
    cases() < 50
}

/// True in CI (`CI=true`, as `.ci/run` sets it) or with `PBGI_DEEP_TESTS`
/// set: the few tests that are slow by nature (long bit-identity sweeps,
/// path-traced references) run at their full depth there, and at a depth
/// that keeps the README's test command within minutes elsewhere.
pub fn deep() -> bool {
    std::env::var("CI").is_ok_and(|v| v == "true") || std::env::var_os("PBGI_DEEP_TESTS").is_some()
}

/// Names of the paths this CPU runs, for the log line of each test.
pub fn path_names() -> String {
    Isa::available()
        .iter()
        .map(|i| i.name())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Leaves `what` out of a test, saying `why`: printed, and appended as a
/// line to the file `PBGI_SKIP_LOG` names, which CI counts in its summary
/// (`cargo test` shows a passing test's output only with `--nocapture`).
pub fn skipped(what: &str, why: &str) {
    use std::io::Write;
    eprintln!("skipped {what}: {why}");
    if let Some(path) = std::env::var_os("PBGI_SKIP_LOG").filter(|p| !p.is_empty()) {
        let line = format!("{}: {what}: {why}\n", env!("CARGO_CRATE_NAME"));
        let appended = std::fs::OpenOptions::new()
            .create(true)
            .append(true)
            .open(&path)
            .and_then(|mut f| f.write_all(line.as_bytes()));
        appended.unwrap_or_else(|e| panic!("PBGI_SKIP_LOG {}: {e}", std::path::Path::new(&path).display()));
    }
}

/// Runs `prop` on `cases()` passing cases (discarded ones do not count).
pub fn qc<P: Testable>(name: &str, prop: P) {
    let n = cases();
    eprintln!("{name}: {n} cases, paths {}", path_names());
    QuickCheck::new()
        .tests(n)
        .max_tests(n * 20)
        .min_tests_passed(n)
        .quickcheck(prop);
}

// ---------------------------------------------------------------------------
// Randomness

/// SplitMix64: the clouds depend on the seed alone, not on a crate's version.
#[derive(Clone, Debug)]
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed ^ 0x6A09_E667_F3BC_C908)
    }

    pub fn u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in `0..n` (`n > 0`).
    pub fn below(&mut self, n: usize) -> usize {
        (self.u64() % n as u64) as usize
    }

    pub fn chance(&mut self, p: f64) -> bool {
        self.unit_f64() < p
    }

    /// Uniform in `[0, 1)`.
    pub fn unit_f64(&mut self) -> f64 {
        (self.u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform in `[lo, hi)`.
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        (lo as f64 + (hi as f64 - lo as f64) * self.unit_f64()) as f32
    }

    /// Log-uniform in `[lo, hi)` (`0 < lo < hi`).
    pub fn log_range(&mut self, lo: f32, hi: f32) -> f32 {
        let (a, b) = ((lo as f64).ln(), (hi as f64).ln());
        ((a + (b - a) * self.unit_f64()).exp() as f32).clamp(lo, hi)
    }

    /// Uniform in the cube `[-1, 1]³`.
    pub fn cube(&mut self) -> Vec3 {
        Vec3::new(
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
        )
    }

    pub fn pick<T: Copy>(&mut self, xs: &[T]) -> T {
        xs[self.below(xs.len())]
    }

    /// Uniform unit vector (normalized in f64, so it passes validation).
    pub fn unit(&mut self) -> Vec3 {
        loop {
            let v = DVec3::new(
                2.0 * self.unit_f64() - 1.0,
                2.0 * self.unit_f64() - 1.0,
                2.0 * self.unit_f64() - 1.0,
            );
            let l = v.length();
            if l > 1e-3 && l <= 1.0 {
                return (v / l).as_vec3();
            }
        }
    }

    /// One of ±X, ±Y, ±Z.
    pub fn axis(&mut self) -> Vec3 {
        self.pick(&[Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z])
    }

    /// A random unit normal: mostly uniform, sometimes axis aligned,
    /// sometimes halfway between two axes, leaning a rounding error to one
    /// (a face at 45°: which axis dominates is a matter of rounding).
    pub fn normal(&mut self) -> Vec3 {
        if self.chance(0.2) {
            self.axis()
        } else if self.chance(0.1) {
            let (i, j) = self.pick(&[(0, 1), (0, 2), (1, 2)]);
            let lean = self.range(-3e-6, 3e-6) as f64;
            let mut v = DVec3::ZERO;
            v[i] = self.pick(&[-1.0, 1.0]) * (1.0 + lean);
            v[j] = self.pick(&[-1.0, 1.0]) * (1.0 - lean);
            (v / v.length()).as_vec3()
        } else {
            self.unit()
        }
    }
}

// ---------------------------------------------------------------------------
// Clouds

/// Kinds of cloud, from benign to adversarial.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Positions uniform in a cube, random normals, radii 0.005..0.1.
    Uniform,
    /// Nearly all surfels at one position (a few at two others); normals
    /// equal, opposite or random (the normal cone can be degenerate).
    Duplicates,
    /// A sheet in one plane, normals the plane's (some flipped), on a grid or random.
    Coplanar,
    /// A line, evenly spaced or random, normals random.
    Collinear,
    /// Clusters of scale 1e-3, 1 and 1e3 in one cloud, radii to match.
    MixedScales,
    /// Radii from 1e-6 to 1e3 in one cloud.
    WildRadii,
    /// A small integer lattice: many ties in every coordinate, axis normals.
    Lattice,
    /// Every surfel drawn from one of the shapes above.
    Mixture,
    /// Coordinates near 1e15 and 1e-15, radii from subnormal (1e-40) to 1e14.
    Extreme,
    /// The crate's synthetic Cornell-box-like interior.
    Box,
}

pub const SHAPES: [Shape; 10] = [
    Shape::Uniform,
    Shape::Duplicates,
    Shape::Coplanar,
    Shape::Collinear,
    Shape::MixedScales,
    Shape::WildRadii,
    Shape::Lattice,
    Shape::Mixture,
    Shape::Extreme,
    Shape::Box,
];

/// A cloud as parameters: `cloud()` makes the surfels.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct CloudSpec {
    pub shape: Shape,
    pub n: usize,
    pub seed: u64,
}

impl fmt::Debug for CloudSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{:?} n={} seed={:#x}", self.shape, self.n, self.seed)
    }
}

/// Per-cloud parameters, drawn before any surfel so that clouds of one seed
/// are prefixes of each other.
struct Params {
    p0: Vec3,
    axis: Vec3,
    tangent: Vec3,
    bitangent: Vec3,
    grid: bool,
    spacing: f32,
    spots: [Vec3; 3],
    clusters: [(Vec3, f32); 3],
}

impl Params {
    fn new(rng: &mut Rng) -> Self {
        let p0 = rng.cube();
        let axis = rng.normal();
        let (tangent, bitangent) = axis.any_orthonormal_pair();
        let grid = rng.chance(0.5);
        let spacing = rng.pick(&[0.01, 0.125, 0.3, 1.0]);
        let spots = [p0, p0 + rng.cube() * 0.1, rng.cube()];
        let mut clusters = [(Vec3::ZERO, 1.0); 3];
        for (i, s) in [1e-3f32, 1.0, 1e3].into_iter().enumerate() {
            // The small cluster sits somewhere inside the big one's range.
            clusters[i] = (rng.cube() * if i == 2 { 1e3 } else { 2.0 }, s);
        }
        Params {
            p0,
            axis,
            tangent,
            bitangent,
            grid,
            spacing,
            spots,
            clusters,
        }
    }
}

/// Position, normal and radius of surfel `i` of a cloud of `shape`.
fn surfel(shape: Shape, i: usize, q: &Params, rng: &mut Rng) -> (Vec3, Vec3, f32) {
    match shape {
        Shape::Uniform => (q.p0 + rng.cube(), rng.normal(), rng.log_range(0.005, 0.1)),
        Shape::Duplicates => {
            let p = if rng.chance(0.85) {
                q.spots[0]
            } else {
                rng.pick(&q.spots)
            };
            let n = match rng.below(4) {
                0 | 1 => q.axis,
                2 => -q.axis,
                _ => rng.normal(),
            };
            let r = if rng.chance(0.5) {
                0.05
            } else {
                rng.log_range(1e-3, 1.0)
            };
            (p, n, r)
        }
        Shape::Coplanar => {
            let (u, v) = if q.grid {
                ((i % 16) as f32 * q.spacing, (i / 16) as f32 * q.spacing)
            } else {
                (rng.range(-1.0, 1.0), rng.range(-1.0, 1.0))
            };
            let n = if rng.chance(0.25) { -q.axis } else { q.axis };
            (q.p0 + q.tangent * u + q.bitangent * v, n, rng.range(0.01, 0.1))
        }
        Shape::Collinear => {
            let t = if q.grid {
                i as f32 * q.spacing
            } else {
                rng.range(-1.0, 1.0)
            };
            let n = if rng.chance(0.3) { q.tangent } else { rng.normal() };
            (
                q.p0 + q.axis * t,
                n,
                if q.grid { 0.02 } else { rng.range(0.001, 0.05) },
            )
        }
        Shape::MixedScales => {
            let (c, s) = rng.pick(&q.clusters);
            (c + rng.cube() * s, rng.normal(), 0.05 * s * rng.range(0.5, 2.0))
        }
        Shape::WildRadii => {
            let r = if rng.chance(0.5) {
                rng.pick(&[1e-6, 1e-3, 1.0, 10.0, 1e3])
            } else {
                rng.log_range(1e-6, 1e3)
            };
            (q.p0 + rng.cube(), rng.normal(), r)
        }
        Shape::Lattice => {
            let c = |rng: &mut Rng| rng.below(4) as f32 * 0.25;
            let p = Vec3::new(c(rng), c(rng), c(rng));
            (p, rng.axis(), rng.pick(&[0.125, 0.3]))
        }
        Shape::Mixture => {
            let kind = rng.pick(&SHAPES[..7]);
            surfel(kind, i, q, rng)
        }
        Shape::Extreme => {
            let s = if rng.chance(0.5) { 1e15 } else { 1e-15 };
            let r = rng.pick(&[1e-40, 1e-30, 1e-15, 1.0, 1e10, 1e14]);
            (rng.cube() * s, rng.normal(), r)
        }
        Shape::Box => unreachable!("made by pbgi::synthetic"),
    }
}

/// The surfels of a spec (radiance random, often zero).
pub fn cloud(spec: &CloudSpec) -> Vec<Surfel> {
    let mut rng = Rng::new(spec.seed);
    if spec.shape == Shape::Box {
        if spec.n == 0 {
            return Vec::new();
        }
        return pbgi::synthetic::box_with_blocks(spec.n, spec.seed).into_surfels();
    }
    let q = Params::new(&mut rng);
    (0..spec.n)
        .map(|i| {
            let (position, normal, radius) = surfel(spec.shape, i, &q, &mut rng);
            let radiance = if rng.chance(0.3) {
                Vec3::ZERO
            } else {
                Vec3::new(rng.range(0.0, 2.0), rng.range(0.0, 2.0), rng.range(0.0, 2.0))
            };
            Surfel {
                position,
                normal,
                radius,
                radiance,
            }
        })
        .collect()
}

/// Scales positions and radii by `s` (a power of two: exact).
pub fn scale_cloud(surfels: &[Surfel], s: f32) -> Vec<Surfel> {
    surfels
        .iter()
        .map(|x| Surfel {
            position: x.position * s,
            radius: x.radius * s,
            ..*x
        })
        .collect()
}

fn shrink_usize(n: usize, min: usize) -> Vec<usize> {
    let mut out = Vec::new();
    for c in [min, n / 2, n - n / 4, n.saturating_sub(1)] {
        if c >= min && c < n && !out.contains(&c) {
            out.push(c);
        }
    }
    out
}

impl CloudSpec {
    /// A spec of at most `max_n` surfels: small sizes are frequent, `0` rare.
    pub fn arbitrary_sized(g: &mut Gen, max_n: usize) -> Self {
        let shape = *g.choose(&SHAPES).unwrap();
        let pick = u64::arbitrary(g);
        let n = match pick % 20 {
            0 => 0,
            1..=3 => 1 + (pick >> 8) as usize % 4,
            4..=8 => 5 + (pick >> 8) as usize % 40,
            _ => 1 + (pick >> 8) as usize % max_n,
        };
        CloudSpec {
            shape,
            n,
            seed: u64::arbitrary(g),
        }
    }

    pub fn shrunk(&self) -> Vec<CloudSpec> {
        let mut out: Vec<_> = shrink_usize(self.n, 0)
            .into_iter()
            .map(|n| CloudSpec { n, ..*self })
            .collect();
        if self.shape == Shape::Mixture {
            // A mixture fails for one of its parts? Try the plain shapes.
            out.extend(SHAPES[..7].iter().map(|&shape| CloudSpec { shape, ..*self }));
        }
        out
    }
}

/// A tree-test cloud: up to 3000 surfels.
#[derive(Clone, Debug)]
pub struct TreeCase(pub CloudSpec);

impl Arbitrary for TreeCase {
    fn arbitrary(g: &mut Gen) -> Self {
        TreeCase(CloudSpec::arbitrary_sized(g, 3000))
    }
    fn shrink(&self) -> Box<dyn Iterator<Item = Self>> {
        Box::new(self.0.shrunk().into_iter().map(TreeCase))
    }
}

// ---------------------------------------------------------------------------
// Receivers and thresholds

/// Receivers as parameters: `count` of them from `seed`, placed relative to the cloud.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct ReceiverSpec {
    pub count: usize,
    pub seed: u64,
}

impl fmt::Debug for ReceiverSpec {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} receivers seed={:#x}", self.count, self.seed)
    }
}

impl ReceiverSpec {
    /// Receiver counts around the packet width are frequent (15, 16, 17, 31, 33...).
    pub fn arbitrary_sized(g: &mut Gen, max: usize) -> Self {
        let pick = u64::arbitrary(g);
        let count = match pick % 6 {
            0 => *g
                .choose(&[1usize, 2, 15, 16, 17, 31, 32, 33, 47, 63, 65])
                .unwrap(),
            _ => 1 + (pick >> 8) as usize % max,
        };
        ReceiverSpec {
            count,
            seed: u64::arbitrary(g),
        }
    }
}

/// Bounding box of the positions, in f64 (the root sphere's centre is its middle).
pub fn bounds(surfels: &[Surfel]) -> (DVec3, DVec3) {
    let mut lo = DVec3::INFINITY;
    let mut hi = DVec3::NEG_INFINITY;
    for s in surfels {
        lo = lo.min(s.position.as_dvec3());
        hi = hi.max(s.position.as_dvec3());
    }
    if surfels.is_empty() {
        (DVec3::splat(-1.0), DVec3::ONE)
    } else {
        (lo, hi)
    }
}

/// Receiver positions and normals for a cloud: on surfels (exactly, `d² = 0`
/// for leaves), at the root's centre, in and around the cloud, far away, just
/// above and below disks, in disk planes (edge on).
pub fn receivers(spec: &ReceiverSpec, surfels: &[Surfel]) -> Vec<(Vec3, Vec3)> {
    let mut rng = Rng::new(spec.seed);
    let (lo, hi) = bounds(surfels);
    let centre = ((lo + hi) * 0.5).as_vec3();
    let ext = (hi - lo).max_element().max(1e-3) as f32;
    let any = |rng: &mut Rng| {
        if surfels.is_empty() {
            Surfel {
                position: rng.cube(),
                normal: rng.unit(),
                radius: 0.1,
                radiance: Vec3::ONE,
            }
        } else {
            surfels[rng.below(surfels.len())]
        }
    };
    (0..spec.count)
        .map(|_| {
            let s = any(&mut rng);
            match rng.below(9) {
                0 => (s.position, s.normal),
                1 => (s.position, if rng.chance(0.5) { -s.normal } else { rng.normal() }),
                2 | 3 => {
                    let t = Vec3::new(rng.range(-0.5, 1.5), rng.range(-0.5, 1.5), rng.range(-0.5, 1.5));
                    (lo.as_vec3() + (hi - lo).as_vec3() * t, rng.normal())
                }
                4 => (centre, rng.normal()),
                5 => {
                    let d = rng.unit();
                    let n = if rng.chance(0.5) { -d } else { rng.normal() };
                    (centre + d * ext * 1e3, n)
                }
                6 => {
                    let side = if rng.chance(0.5) { 1.0 } else { -1.0 };
                    let p = s.position + s.normal * (side * s.radius * rng.pick(&[1e-6, 1e-3, 0.5, 3.0]));
                    (p, if rng.chance(0.5) { s.normal } else { rng.normal() })
                }
                7 => {
                    // In the disk's plane: edge on.
                    let (t, b) = s.normal.any_orthonormal_pair();
                    let a = rng.range(0.0, std::f32::consts::TAU);
                    let p = s.position + (t * a.cos() + b * a.sin()) * s.radius * rng.range(0.0, 3.0);
                    (p, if rng.chance(0.5) { s.normal } else { t })
                }
                _ => (
                    s.position + rng.unit() * s.radius * rng.range(0.0, 4.0),
                    rng.normal(),
                ),
            }
        })
        .collect()
}

/// Ω: zero, tiny, typical, huge and random, with the float edge cases.
pub fn arbitrary_omega(g: &mut Gen) -> f32 {
    let mut rng = Rng::new(u64::arbitrary(g));
    match rng.below(14) {
        0 => 0.0,
        1 => 1e-6,
        2 => rng.log_range(1e-9, 1e-4),
        3..=6 => rng.range(0.01, 0.3),
        7 => 1e3,
        8 => 4.0 * std::f32::consts::PI,
        9 => rng.range(0.0, 2.0),
        10 => rng.log_range(1e-8, 1e4),
        11 => rng.pick(&[f32::MIN_POSITIVE, 1e-40, f32::MAX]),
        _ => rng.pick(&[0.01, 0.05, 0.3]),
    }
}

/// One traversal case: a cloud, receivers, Ω and the hybrid threshold.
#[derive(Clone)]
pub struct Case {
    pub cloud: CloudSpec,
    pub receivers: ReceiverSpec,
    pub omega: f32,
    /// The light offset's weight `k` in the far test.
    pub light_offset: f32,
    pub threshold: u32,
}

impl fmt::Debug for Case {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "Case {{ {:?}, {:?}, Ω={:e}, k={}, hybrid_threshold={} }}",
            self.cloud, self.receivers, self.omega, self.light_offset, self.threshold
        )
    }
}

impl Arbitrary for Case {
    fn arbitrary(g: &mut Gen) -> Self {
        Case {
            cloud: CloudSpec::arbitrary_sized(g, 400),
            receivers: ReceiverSpec::arbitrary_sized(g, 80),
            omega: arbitrary_omega(g),
            // Half the cases the plain test, the others a weight up to 8.
            light_offset: if bool::arbitrary(g) {
                0.0
            } else {
                (u32::arbitrary(g) % 33) as f32 / 4.0
            },
            threshold: u32::arbitrary(g) % 18,
        }
    }

    fn shrink(&self) -> Box<dyn Iterator<Item = Self>> {
        let mut out = Vec::new();
        for cloud in self.cloud.shrunk() {
            out.push(Case {
                cloud,
                ..self.clone()
            });
        }
        for count in shrink_usize(self.receivers.count, 1) {
            out.push(Case {
                receivers: ReceiverSpec {
                    count,
                    ..self.receivers
                },
                ..self.clone()
            });
        }
        for omega in [0.0, 0.05] {
            if self.omega != omega {
                out.push(Case {
                    omega,
                    ..self.clone()
                });
            }
        }
        if self.threshold != 2 {
            out.push(Case {
                threshold: 2,
                ..self.clone()
            });
        }
        if self.light_offset != 0.0 {
            out.push(Case {
                light_offset: 0.0,
                ..self.clone()
            });
        }
        Box::new(out.into_iter())
    }
}

impl Case {
    pub fn surfels(&self) -> Vec<Surfel> {
        cloud(&self.cloud)
    }

    pub fn receivers(&self, surfels: &[Surfel]) -> Vec<Receiver> {
        let pairs = receivers(&self.receivers, surfels);
        Receiver::from_pairs(pairs).expect("generated receivers are valid")
    }
}

// ---------------------------------------------------------------------------
// Independent checkers

/// docs/design.md §2's invariants, checked from the parent links (not with
/// `Cut::check`): ids in range, sorted, no duplicates, splats and discards
/// disjoint; every leaf has exactly one splatted-or-discarded node on its path
/// to the root; no splatted (or discarded) node has a marked strict ancestor.
pub fn invariants(tree: &Tree, parents: &[Option<NodeId>], cut: &Cut) -> Result<(), String> {
    let n = tree.len();
    if n == 0 {
        return if cut.splats.is_empty() && cut.discards.is_empty() {
            Ok(())
        } else {
            Err(format!("empty tree, non-empty cut {cut:?}"))
        };
    }
    for (what, list) in [("splats", &cut.splats), ("discards", &cut.discards)] {
        if let Some(w) = list.windows(2).find(|w| w[0] >= w[1]) {
            return Err(format!("{what} not strictly increasing: {} then {}", w[0], w[1]));
        }
        if let Some(&k) = list.iter().find(|&&k| k as usize >= n) {
            return Err(format!("{what} holds node {k}, tree has {n}"));
        }
    }
    let mut marked = vec![0u8; n];
    for &k in cut.splats.iter().chain(&cut.discards) {
        marked[k as usize] += 1;
        if marked[k as usize] > 1 {
            return Err(format!("node {k} is both splatted and discarded"));
        }
    }
    for k in 0..n as NodeId {
        if tree.node(k).children.is_none() {
            let mut count = 0;
            let mut x = Some(k);
            while let Some(y) = x {
                count += marked[y as usize] as u32;
                x = parents[y as usize];
            }
            if count != 1 {
                return Err(format!(
                    "leaf {k} has {count} splatted/discarded ancestors-or-self"
                ));
            }
        }
    }
    for (what, list) in [("splatted", &cut.splats), ("discarded", &cut.discards)] {
        for &k in list {
            let mut x = parents[k as usize];
            while let Some(y) = x {
                if marked[y as usize] != 0 {
                    return Err(format!("{what} node {k} lies below cut node {y}"));
                }
                x = parents[y as usize];
            }
        }
    }
    Ok(())
}

/// Parent links derived from `node(k).children` alone.
pub fn parents_from_nodes(tree: &Tree) -> Vec<Option<NodeId>> {
    let mut p = vec![None; tree.len()];
    for k in 0..tree.len() as NodeId {
        if let Some(l) = tree.node(k).children {
            p[l as usize] = Some(k);
            p[l as usize + 1] = Some(k);
        }
    }
    p
}

/// Surfel indices below every node (each node's list, in tree order).
pub fn surfels_below(tree: &Tree) -> Vec<Vec<u32>> {
    let mut out = vec![Vec::new(); tree.len()];
    if tree.is_empty() {
        return out;
    }
    // Post-order without recursion: children have larger ids than parents, so
    // walking ids downwards visits children first.
    for k in (0..tree.len() as NodeId).rev() {
        let v = tree.node(k);
        out[k as usize] = match (v.children, v.surfel) {
            (Some(l), _) => {
                let mut a = out[l as usize].clone();
                a.extend_from_slice(&out[l as usize + 1]);
                a
            }
            (None, Some(s)) => vec![s],
            (None, None) => panic!("node {k} is neither inner nor leaf"),
        };
    }
    out
}

/// The node test of docs/design.md §2 re-derived in f64 from the stored f32 node, with
/// tolerances for the kernels' f32 rounding: `Some(true)` when the f64 test
/// clearly says yes, `Some(false)` clearly no, `None` within rounding.
pub struct NodeTest64 {
    pub below: Option<bool>,
    pub faces_away: Option<bool>,
    pub far: Option<bool>,
}

fn decide(lhs: f64, rhs: f64, tol: f64) -> Option<bool> {
    // `lhs <= rhs` (or `<`, equal within tolerance either way).
    if lhs <= rhs - tol {
        Some(true)
    } else if lhs > rhs + tol {
        Some(false)
    } else {
        None
    }
}

pub fn node_test64(v: &NodeView, x: Vec3, n: Vec3, omega: f32, k: f32) -> NodeTest64 {
    let (c, x, n) = (v.center.as_dvec3(), x.as_dvec3(), n.as_dvec3());
    let r = v.radius as f64;
    // The far test's radius: `R + k·|l − c|` (light and area centroids),
    // the offset as the tree holds it.
    let split = r + k as f64 * v.light_offset as f64;
    let d = c - x;
    let len = d.length();
    // f32 evaluation errors are relative to |v| and R (v = c − x is one
    // rounding, the dot and cross products a few more); 1e-5 is generous.
    let tol = 1e-5 * (len + r) + 1e-35;
    let below = decide(d.dot(n), -r, tol);
    let a = v.cone_axis.as_dvec3();
    let (cos, sin) = (v.cone_cos as f64, v.cone_sin as f64);
    let s = a.cross(d).length();
    let faces_away = decide(sin * s + r, cos * a.dot(d), 3.0 * tol);
    let pi_r2 = std::f64::consts::PI * split * split;
    let od2 = omega as f64 * len * len;
    // `π S² < Ω d²`, with a relative tolerance and room for f32 underflow.
    let far = decide(pi_r2, od2, 1e-5 * (pi_r2 + od2) + 1e-36);
    NodeTest64 {
        below,
        faces_away,
        far,
    }
}

/// The cut's outcomes checked against the f64 node test and against geometry:
///
/// * a splatted node is not clearly discardable, and is a leaf or clearly not
///   too near (`π S² < Ω d²` up to rounding, `S = R + k·|l − c|` at the
///   light offset weight `k`);
/// * a discarded node is below the tangent plane or faces away (up to
///   rounding), and each of its disks really is invisible: wholly below the
///   receiver's tangent plane, or the receiver lies behind the disk's plane;
/// * a traversed node (a strict ancestor of the cut) is neither clearly
///   discardable nor clearly far;
/// * with Ω = 0 only leaves are splatted (exactly).
pub fn semantics(
    tree: &Tree,
    parents: &[Option<NodeId>],
    below_lists: &[Vec<u32>],
    surfels: &[Surfel],
    rec: &Receiver,
    (omega, weight): (f32, f32),
    cut: &Cut,
) -> Result<(), String> {
    let (x, n) = (rec.position(), rec.normal());
    let discardable = |t: &NodeTest64| t.below == Some(true) || t.faces_away == Some(true);
    let kept = |t: &NodeTest64| t.below == Some(false) && t.faces_away == Some(false);
    for &k in &cut.splats {
        let v = tree.node(k);
        let t = node_test64(&v, x, n, omega, weight);
        if discardable(&t) {
            return Err(format!(
                "splatted node {k} is clearly discardable (below {:?}, faces away {:?})",
                t.below, t.faces_away
            ));
        }
        if v.children.is_some() {
            if omega == 0.0 {
                return Err(format!("Ω = 0 splats inner node {k}"));
            }
            if t.far == Some(false) {
                return Err(format!(
                    "splatted inner node {k} is too near: π S² ≥ Ω d² = {:e} (R {:e}, light offset {:e})",
                    omega as f64 * (v.center.as_dvec3() - x.as_dvec3()).length_squared(),
                    v.radius,
                    v.light_offset
                ));
            }
        }
    }
    for &k in &cut.discards {
        let v = tree.node(k);
        let t = node_test64(&v, x, n, omega, weight);
        if kept(&t) {
            return Err(format!(
                "discarded node {k} is clearly neither below nor facing away"
            ));
        }
        // Geometry: every disk below it is invisible from the receiver.
        let (xd, nd) = (x.as_dvec3(), n.as_dvec3());
        let tol = 1e-5 * ((v.center.as_dvec3() - xd).length() + v.radius as f64) + 1e-35;
        for &i in &below_lists[k as usize] {
            let s = &surfels[i as usize];
            let (p, m, r) = (s.position.as_dvec3(), s.normal.as_dvec3(), s.radius as f64);
            let top = (p - xd).dot(nd) + r * (1.0 - m.dot(nd).powi(2)).max(0.0).sqrt();
            let front = m.dot(xd - p) / m.length();
            if top > tol && front > tol {
                return Err(format!(
                    "discarded node {k} holds surfel {i} visible from the receiver \
                     (disk top {top:e} above the tangent plane, receiver {front:e} in front of the disk)"
                ));
            }
        }
    }
    // Traversed nodes: strict ancestors of cut nodes.
    let mut traversed = vec![false; tree.len()];
    for &k in cut.splats.iter().chain(&cut.discards) {
        let mut y = parents[k as usize];
        while let Some(p) = y {
            if std::mem::replace(&mut traversed[p as usize], true) {
                break;
            }
            y = parents[p as usize];
        }
    }
    for (k, _) in traversed.iter().enumerate().filter(|(_, t)| **t) {
        let v = tree.node(k as NodeId);
        let t = node_test64(&v, x, n, omega, weight);
        if discardable(&t) {
            return Err(format!("traversed node {k} is clearly discardable"));
        }
        if t.far == Some(true) {
            return Err(format!("traversed node {k} is clearly far enough to splat"));
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// Every scheme on every path

/// A sink without discards (the kernels skip that bookkeeping: another code path).
pub struct SplatsOnly(pub Vec<Vec<NodeId>>);

impl CutSink for SplatsOnly {
    fn splat(&mut self, receiver: usize, node: NodeId) {
        self.0[receiver].push(node);
    }
}

/// The first difference between two cut lists, for messages.
pub fn first_difference(got: &[Cut], want: &[Cut]) -> Option<String> {
    if got.len() != want.len() {
        return Some(format!("{} cuts, expected {}", got.len(), want.len()));
    }
    let i = (0..got.len()).find(|&i| got[i] != want[i])?;
    let diff = |a: &[NodeId], b: &[NodeId]| {
        a.iter()
            .filter(|x| !b.contains(x))
            .take(8)
            .copied()
            .collect::<Vec<_>>()
    };
    Some(format!(
        "receiver {i}: splats +{:?} −{:?}, discards +{:?} −{:?}",
        diff(&got[i].splats, &want[i].splats),
        diff(&want[i].splats, &got[i].splats),
        diff(&got[i].discards, &want[i].discards),
        diff(&want[i].discards, &got[i].discards),
    ))
}

pub fn traversal(tree: &Tree, omega: f32, k: f32, threshold: u32, isa: Isa) -> Result<Traversal<'_>, String> {
    let t = Traversal::new(
        tree,
        CutOptions {
            max_solid_angle: omega,
            light_offset: k,
            hybrid_threshold: threshold,
            isa: Some(isa),
        },
    )
    .map_err(|e| format!("Traversal::new on {isa}: {e}"))?;
    if t.isa() != isa {
        return Err(format!("asked for {isa}, runs on {}", t.isa()));
    }
    Ok(t)
}

/// Every scheme on every path against the scalar cut of the first path, through
/// `cuts`, through `run` (whole slice, stats), with a discard-free sink and
/// with the splat counter. Returns the scalar cuts.
pub fn all_paths_agree(
    tree: &Tree,
    receivers: &[Receiver],
    omega: f32,
    k: f32,
    threshold: u32,
) -> Result<Vec<Cut>, String> {
    let mut reference: Option<Vec<Cut>> = None;
    for isa in Isa::available() {
        let t = traversal(tree, omega, k, threshold, isa)?;
        let scalar = t.cuts(Scheme::Scalar, receivers);
        if let Some(r) = &reference
            && let Some(d) = first_difference(&scalar, r)
        {
            return Err(format!("scalar on {isa} differs from the first path at {d}"));
        }
        for scheme in [Scheme::Single, Scheme::Packet, Scheme::Hybrid] {
            if let Some(d) = first_difference(&t.cuts(scheme, receivers), &scalar) {
                return Err(format!("{scheme} on {isa} (cuts) differs from scalar at {d}"));
            }
        }

        // The counters: every scheme tests the same (receiver, node) pairs,
        // the cut nodes and their strict ancestors (2|C| − 1 in a full binary tree).
        let expected_tests: u64 = if tree.is_empty() {
            0
        } else {
            scalar
                .iter()
                .map(|c| 2 * (c.splats.len() + c.discards.len()) as u64 - 1)
                .sum()
        };
        let total_splats: u64 = scalar.iter().map(|c| c.splats.len() as u64).sum();
        for scheme in Scheme::ALL {
            let mut rec = CutRecorder::new(receivers.len());
            let stats = t.run(scheme, receivers, &mut rec);
            if let Some(d) = first_difference(&rec.into_cuts(), &scalar) {
                return Err(format!("{scheme} on {isa} (run) differs from scalar at {d}"));
            }
            let fail = |what: &str| Err(format!("{scheme} on {isa}: {what}: {stats:?}"));
            if stats.receivers != receivers.len() as u64 {
                return fail("receiver count");
            }
            if stats.node_tests != expected_tests {
                return fail(&format!("node tests, expected {expected_tests}"));
            }
            match scheme {
                Scheme::Scalar if stats.lane_slots != 0 || stats.active_lanes != 0 => return fail("lanes"),
                Scheme::Scalar => {}
                _ if stats.lane_slots % 16 != 0 || stats.active_lanes != stats.node_tests => {
                    return fail("lanes");
                }
                _ => {}
            }
            let chunks = receivers.len().div_ceil(16) as u64;
            let switches_ok = match (scheme, threshold) {
                (Scheme::Hybrid, 0 | 1) => stats.switches == 0,
                (Scheme::Hybrid, 17) => stats.switches == if tree.is_empty() { 0 } else { chunks },
                (Scheme::Hybrid, _) => true,
                _ => stats.switches == 0,
            };
            if !switches_ok {
                return fail(&format!("switches with threshold {threshold}"));
            }

            let mut only = SplatsOnly(vec![Vec::new(); receivers.len()]);
            t.run(scheme, receivers, &mut only);
            for (i, mut s) in only.0.into_iter().enumerate() {
                s.sort_unstable();
                if s != scalar[i].splats {
                    return Err(format!(
                        "{scheme} on {isa} without discards: receiver {i} splats {s:?}, scalar {:?}",
                        scalar[i].splats
                    ));
                }
            }
            let mut count = SplatCounter::default();
            t.run(scheme, receivers, &mut count);
            if count.splats != total_splats {
                return Err(format!(
                    "{scheme} on {isa}: splat counter {} vs {total_splats}",
                    count.splats
                ));
            }
        }
        reference.get_or_insert(scalar);
    }
    Ok(reference.unwrap_or_default())
}

// ---------------------------------------------------------------------------
// Shading

/// The shading pipelines: the scalar one (each receiver's cut as a list,
/// splatted one node at a time: `shade_cuts`) and the 16-lane one (a packet's
/// cut as nodes with their lanes: `shade_packet`). The renderer shades the
/// scalar scheme through the first and every other scheme through the second.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Pipeline {
    Scalar,
    Lanes,
}

impl Pipeline {
    pub const ALL: [Pipeline; 2] = [Pipeline::Scalar, Pipeline::Lanes];

    /// The pipeline the renderer uses for `scheme`.
    pub fn of(scheme: Scheme) -> Pipeline {
        match scheme {
            Scheme::Scalar => Pipeline::Scalar,
            _ => Pipeline::Lanes,
        }
    }
}

/// What a receiver's microbuffer gives: irradiance, occlusion (both from the
/// pipeline's own convolution) and glossy radiance for [`GLOSSY_PROBES`]
/// (the buffer's glossy convolution over what the pipeline splatted).
#[derive(Clone, Copy, Debug)]
pub struct Shaded {
    pub irradiance: Vec3,
    pub occlusion: f32,
    pub glossy: [Vec3; 2],
}

impl Shaded {
    pub fn bits(&self) -> [u32; 10] {
        let (e, g0, g1) = (self.irradiance, self.glossy[0], self.glossy[1]);
        [e.x, e.y, e.z, self.occlusion, g0.x, g0.y, g0.z, g1.x, g1.y, g1.z].map(f32::to_bits)
    }
}

/// The glossy lobes and outgoing directions (in the receiver's frame: x
/// tangent, z normal) every shading is probed with: a sharp lobe seen at 45°
/// and a wide one seen near grazing.
pub const GLOSSY_PROBES: [(f32, [f32; 3]); 2] = [(0.2, [0.6, 0.0, 0.8]), (1.0, [0.95, 0.0, 0.3122499])];

/// A sink keeping each receiver's splats in traversal order (as the
/// renderer's scalar pipeline receives them).
struct Lists(Vec<Vec<NodeId>>);

impl CutSink for Lists {
    fn splat(&mut self, receiver: usize, node: NodeId) {
        self.0[receiver].push(node);
    }
}

/// Shades `receivers` (packets of 16): the cut of `scheme` on `isa`, splatted
/// through `pipeline` into microbuffers of resolution `res`.
pub fn shade_with(
    tree: &Tree,
    receivers: &[Receiver],
    omega: f32,
    res: usize,
    scheme: Scheme,
    isa: Isa,
    pipeline: Pipeline,
) -> Result<Vec<Shaded>, String> {
    shade_pipeline(tree, receivers, omega, res, scheme, isa, pipeline, true)
}

/// [`shade_with`]'s irradiance alone (no occlusion or glossy pass: the
/// high-resolution analytic cases).
pub fn irradiance_with(
    tree: &Tree,
    receivers: &[Receiver],
    omega: f32,
    res: usize,
    scheme: Scheme,
    isa: Isa,
    pipeline: Pipeline,
) -> Result<Vec<Vec3>, String> {
    let s = shade_pipeline(tree, receivers, omega, res, scheme, isa, pipeline, false)?;
    Ok(s.iter().map(|s| s.irradiance).collect())
}

#[allow(clippy::too_many_arguments)]
fn shade_pipeline(
    tree: &Tree,
    receivers: &[Receiver],
    omega: f32,
    res: usize,
    scheme: Scheme,
    isa: Isa,
    pipeline: Pipeline,
    all: bool,
) -> Result<Vec<Shaded>, String> {
    use pbgi::brdf::GlossyLobe;
    use pbgi::microbuffer::{Convolution, MicroBuffer, PacketCut, shade_cuts, shade_packet};
    let t = traversal(tree, omega, 0.0, 2, isa)?;
    let proto = MicroBuffer::new(res).map_err(|e| e.to_string())?;
    let mut out = Vec::with_capacity(receivers.len());
    for chunk in receivers.chunks(pbgi::LANES) {
        let mut buffers = vec![proto.clone(); chunk.len()];
        // Each receiver's list (scalar pipeline) or the packet's cut (16 lanes).
        let mut lists = Lists(vec![Vec::new(); chunk.len()]);
        let mut cut = PacketCut::new(tree);
        match pipeline {
            Pipeline::Scalar => t.run(scheme, chunk, &mut lists),
            Pipeline::Lanes => t.run(scheme, chunk, &mut cut),
        };
        // Occlusion first: the buffers keep the irradiance pass's splats for glossy.
        let whats = if all {
            vec![Convolution::Occlusion, Convolution::Irradiance]
        } else {
            vec![Convolution::Irradiance]
        };
        let mut passes: Vec<Vec<Vec3>> = whats
            .into_iter()
            .map(|what| {
                for (b, r) in buffers.iter_mut().zip(chunk) {
                    b.reset(r.position(), r.normal());
                }
                let mut values = vec![Vec3::ZERO; chunk.len()];
                match pipeline {
                    Pipeline::Scalar => shade_cuts(isa, &mut buffers, tree, &lists.0, what, &mut values),
                    Pipeline::Lanes => {
                        shade_packet(isa, &mut buffers, tree, &mut cut.clone(), what, &mut values)
                    }
                }
                .unwrap();
                values
            })
            .collect();
        let irradiance = passes.pop().expect("the irradiance pass");
        let occlusion = passes.pop().unwrap_or_else(|| vec![Vec3::ZERO; chunk.len()]);
        for (i, (b, r)) in buffers.iter().zip(chunk).enumerate() {
            let n = r.normal();
            let tangent = n.any_orthonormal_vector();
            let bitangent = n.cross(tangent);
            let glossy = GLOSSY_PROBES.map(|(roughness, [x, y, z])| {
                if !all {
                    return Vec3::ZERO;
                }
                let wo = (tangent * x + bitangent * y + n * z).normalize();
                b.glossy(
                    tree,
                    wo,
                    &GlossyLobe {
                        specular: Vec3::ONE,
                        roughness,
                    },
                )
            });
            out.push(Shaded {
                irradiance: irradiance[i],
                occlusion: occlusion[i].x,
                glossy,
            });
        }
    }
    Ok(out)
}

/// Irradiance and ambient occlusion at each receiver: the cut of `scheme` on
/// `isa` through the pipeline the renderer uses for it.
pub fn shade(
    tree: &Tree,
    receivers: &[Receiver],
    omega: f32,
    res: usize,
    scheme: Scheme,
    isa: Isa,
) -> Result<Vec<(Vec3, f32)>, String> {
    let s = shade_with(tree, receivers, omega, res, scheme, isa, Pipeline::of(scheme))?;
    Ok(s.iter().map(|s| (s.irradiance, s.occlusion)).collect())
}

/// [`shade_with`] with every scheme on every path this CPU runs, through both
/// pipelines: all must give the scalar result of the portable path bit for
/// bit, irradiance, occlusion and glossy alike (docs/design.md §3). Returns
/// its irradiance and occlusion, having checked its glossy radiance is
/// finite and ≥ 0.
pub fn shade_everywhere(
    tree: &Tree,
    receivers: &[Receiver],
    omega: f32,
    res: usize,
) -> Result<Vec<(Vec3, f32)>, String> {
    let reference = shade_with(
        tree,
        receivers,
        omega,
        res,
        Scheme::Scalar,
        Isa::Portable,
        Pipeline::Scalar,
    )?;
    for isa in Isa::available() {
        for scheme in Scheme::ALL {
            for pipeline in Pipeline::ALL {
                let got = shade_with(tree, receivers, omega, res, scheme, isa, pipeline)?;
                if let Some(i) = (0..got.len()).find(|&i| got[i].bits() != reference[i].bits()) {
                    return Err(format!(
                        "{scheme} on {isa}, {pipeline:?} pipeline, Ω {omega:e}, N {res}: receiver {i} shades {:?}, scalar on portable {:?}",
                        got[i], reference[i]
                    ));
                }
            }
        }
    }
    for (i, s) in reference.iter().enumerate() {
        for g in s.glossy {
            if !(g.is_finite() && g.min_element() >= 0.0) {
                return Err(format!("receiver {i}: glossy radiance {g} is not finite and ≥ 0"));
            }
        }
    }
    Ok(reference.iter().map(|s| (s.irradiance, s.occlusion)).collect())
}

/// The energy bounds: irradiance finite, ≥ 0 and at most `π · max L` per
/// channel (coverage ≤ 1 per pixel and `Σ ∫cosθ dω = π`; the slack is f32
/// rounding of the pixel sums: relative, and absolute for subnormal radiance,
/// where each term rounds by up to 2⁻¹⁴⁹), ambient occlusion in [0, 1].
pub fn check_bounded(shading: &[(Vec3, f32)], max_radiance: Vec3) -> Result<(), String> {
    let bound = max_radiance * std::f32::consts::PI * 1.0001 + Vec3::splat(f32::MIN_POSITIVE);
    for (i, &(e, ao)) in shading.iter().enumerate() {
        if !(e.is_finite() && e.min_element() >= 0.0) {
            return Err(format!("receiver {i}: irradiance {e} is not finite and ≥ 0"));
        }
        if e.cmpgt(bound).any() {
            return Err(format!("receiver {i}: irradiance {e} above π·max L = {bound}"));
        }
        if !(0.0..=1.0).contains(&ao) {
            return Err(format!("receiver {i}: occlusion {ao} outside [0, 1]"));
        }
    }
    Ok(())
}

/// `∫ L(p(ω)) n·ω dω` over the hemisphere about unit `n` at `q` inside or
/// on the unit sphere about the origin, `p(ω)` where the ray from `q` along `ω` leaves it: by the
/// midpoint rule in `(sin²θ, φ)`, where the cosine weight is uniform.
pub fn irradiance_in_sphere(q: Vec3, n: Vec3, radiance: impl Fn(Vec3) -> f64) -> f64 {
    let (q, n) = (q.as_dvec3(), n.as_dvec3());
    let (t, b) = n.any_orthonormal_pair();
    let (m, k) = (600, 1200);
    let mut e = 0.0;
    for i in 0..m {
        let s2 = (i as f64 + 0.5) / m as f64;
        let (sin, cos) = (s2.sqrt(), (1.0 - s2).sqrt());
        for j in 0..k {
            let phi = std::f64::consts::TAU * (j as f64 + 0.5) / k as f64;
            let w = t * (sin * phi.cos()) + b * (sin * phi.sin()) + n * cos;
            let qw = q.dot(w);
            // At most zero under the root only for `q` on the sphere, off
            // by rounding.
            let d = -qw + (qw * qw - q.length_squared() + 1.0).max(0.0).sqrt();
            e += radiance((q + w * d).as_vec3());
        }
    }
    // ½ dμ dφ per sample: μ = sin²θ, dω·cosθ = ½ dμ dφ.
    0.5 * e / (m * k) as f64 * std::f64::consts::TAU
}

/// Largest radiance per channel of a cloud.
pub fn max_radiance(surfels: &[Surfel]) -> Vec3 {
    surfels.iter().fold(Vec3::ZERO, |m, s| m.max(s.radiance))
}

/// Every field of every node is finite (nothing non-finite leaves the tree).
pub fn tree_is_finite(tree: &Tree) -> Result<(), String> {
    for k in 0..tree.len() as NodeId {
        let v = tree.node(k);
        let ok = v.center.is_finite()
            && v.radius.is_finite()
            && v.cone_axis.is_finite()
            && v.cone_cos.is_finite()
            && v.cone_sin.is_finite()
            && v.area.is_finite()
            && v.normal.is_finite()
            && v.radiance.is_finite();
        if !ok {
            return Err(format!("node {k} is not finite: {v:?}"));
        }
    }
    Ok(())
}

/// The `pbgi` binary, through cargo's target runner when the tests run
/// under one (qemu for a cross-compiled target): the binary is built for
/// the target, not for the machine that spawns it.
#[cfg(feature = "cli")]
pub fn pbgi_command() -> std::process::Command {
    let runner = std::env::vars()
        .find(|(k, _)| k.starts_with("CARGO_TARGET_") && k.ends_with("_RUNNER"))
        .map(|(_, v)| v);
    let bin = env!("CARGO_BIN_EXE_pbgi");
    let mut words = runner.as_deref().map(str::split_whitespace);
    match words.as_mut().and_then(|w| w.next()) {
        Some(program) => {
            let mut c = std::process::Command::new(program);
            c.args(words.into_iter().flatten()).arg(bin);
            c
        }
        None => std::process::Command::new(bin),
    }
}
