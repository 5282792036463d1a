//! What a traversal is asked for: the scheme and the cut's parameters.

use std::fmt;
use std::str::FromStr;

use crate::error::Error;
use crate::simd::Isa;

/// How the traversal is vectorized.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Scheme {
    /// The reference: one receiver, one node at a time.
    Scalar,
    /// One receiver, 16 nodes at a time.
    Single,
    /// 16 receivers, one node at a time.
    Packet,
    /// Packet, handing an entry to single once fewer than
    /// [`CutOptions::hybrid_threshold`] of its lanes are active.
    Hybrid,
}

impl Scheme {
    /// All schemes, the reference first.
    pub const ALL: [Scheme; 4] = [Scheme::Scalar, Scheme::Single, Scheme::Packet, Scheme::Hybrid];

    /// Lower-case name.
    pub fn name(self) -> &'static str {
        match self {
            Scheme::Scalar => "scalar",
            Scheme::Single => "single",
            Scheme::Packet => "packet",
            Scheme::Hybrid => "hybrid",
        }
    }
}

impl fmt::Display for Scheme {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// Packets of fewer receivers than this run [`Scheme::Single`] under
/// [`auto_scheme`]. Packet costs about as much per node step with one active
/// lane as with sixteen (≈3.5 scalar node tests, from its 4.3–4.9× speed-up
/// at ~85 % lane use), single ≈0.5 per receiver and node: below about six
/// receivers one at a time is cheaper.
pub const AUTO_SINGLE_BELOW: usize = 6;

/// The scheme the `auto` choice runs on one packet of `receivers` receivers:
/// [`Scheme::Packet`], the fastest on every scene measured (docs/lab/BENCHMARKS.md,
/// the glossy and bump ones included, where hybrid's switching cost more than
/// it saved; and on the world-space cache's records, whose packets keep
/// about half their lanes busy, `docs/lab/cache.md`), and [`Scheme::Single`] for packets too sparse to fill lanes
/// (tiles at the image's edge or at silhouettes against the background).
/// Every scheme gives the same cut, so the choice changes only the time.
pub fn auto_scheme(receivers: usize) -> Scheme {
    if receivers < AUTO_SINGLE_BELOW {
        Scheme::Single
    } else {
        Scheme::Packet
    }
}

impl FromStr for Scheme {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        Scheme::ALL
            .into_iter()
            .find(|x| x.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| Error::UnknownScheme { value: s.to_string() })
    }
}

/// Which scheme a caller runs: one named scheme, or per packet the one
/// [`auto_scheme`] picks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SchemeChoice {
    /// Per packet, [`auto_scheme`]: packet, single for sparse packets.
    Auto,
    /// A named scheme.
    Fixed(Scheme),
}

impl SchemeChoice {
    /// The scheme for a packet of `receivers` receivers.
    pub fn resolve(self, receivers: usize) -> Scheme {
        match self {
            SchemeChoice::Auto => auto_scheme(receivers),
            SchemeChoice::Fixed(s) => s,
        }
    }
}

impl fmt::Display for SchemeChoice {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SchemeChoice::Auto => f.write_str("auto"),
            SchemeChoice::Fixed(s) => s.fmt(f),
        }
    }
}

impl FromStr for SchemeChoice {
    type Err = Error;
    /// `auto` or a scheme name.
    fn from_str(s: &str) -> Result<Self, Error> {
        if s.trim().eq_ignore_ascii_case("auto") {
            Ok(SchemeChoice::Auto)
        } else {
            s.parse().map(SchemeChoice::Fixed)
        }
    }
}

/// Traversal parameters.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CutOptions {
    /// Ω: a node is splatted when its disk of radius R subtends less than
    /// this, `π R² < Ω d²` (steradians, ≥ 0; 0 splats leaves only).
    pub max_solid_angle: f32,
    /// `k`: a node counts as larger by `k` times how far its light centroid
    /// lies from its area centroid, `π (R + k·|l − c|)² < Ω d²` (≥ 0; 0: the
    /// plain test). A cluster is drawn as one splat at its area centroid,
    /// so a cluster whose light lies off its centre (a small bright light
    /// in a dark ceiling) shows that light up to `R` from where it lies.
    /// Irradiance reads only the sum and barely minds (the light centroid
    /// sets it); a glossy lobe, or a slab's edge hiding part of the
    /// cluster, reads it where it is drawn. Refined that much more, such
    /// clusters split until their light lies where their surface does:
    /// mid-wall in the light room at Ω 0.2, N 24, glossy 21 → 3.2 % at `k`
    /// 4, irradiance behind a slab 17 → 5.8 %.
    pub light_offset: f32,
    /// Hybrid: an entry with fewer active lanes than this goes to single
    /// (0 never switches, 17 always does).
    pub hybrid_threshold: u32,
    /// Instruction-set path: `None` takes `PBGI_ISA` if set, else the best
    /// this CPU runs.
    pub isa: Option<Isa>,
}

impl Default for CutOptions {
    fn default() -> Self {
        Self {
            max_solid_angle: 0.05,
            light_offset: 0.0,
            hybrid_threshold: 2,
            isa: None,
        }
    }
}
