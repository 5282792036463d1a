//! Run-time dispatch: the kernels are written once (generic, `#[inline(always)]`)
//! and compiled here into one clone per instruction set with
//! `multiversion::target`. The caller may force a clone (API or `PBGI_ISA`);
//! asking for one the CPU lacks is an error, never an illegal instruction.

use std::fmt;
use std::str::FromStr;

use super::node_test::LANES;
use super::{CutSink, Receiver, Scheme, Traversal, TraversalStats, packet, scalar, single};
use crate::error::Error;

/// An instruction-set path of the kernels.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Isa {
    /// x86-64 with AVX-512 (F, BW, CD, DQ, VL and, unless the crate is built
    /// with `--cfg multiversion_allow_slow_avx512`, the Ice Lake extensions
    /// multiversion adds): 16 lanes in one zmm register.
    Avx512,
    /// x86-64 with AVX2 and FMA: two ymm registers per vector.
    Avx2,
    /// AArch64 with NEON: four q registers per vector.
    Neon,
    /// Whatever the compilation target guarantees (SSE2 on x86-64).
    Portable,
}

/// Features the AVX-512 clone is compiled with; multiversion widens any
/// AVX-512 target to this set unless `multiversion_allow_slow_avx512` is set.
#[cfg(target_arch = "x86_64")]
macro_rules! avx512_detected {
    () => {{
        let base = std::arch::is_x86_feature_detected!("avx512f")
            && std::arch::is_x86_feature_detected!("avx512bw")
            && std::arch::is_x86_feature_detected!("avx512cd")
            && std::arch::is_x86_feature_detected!("avx512dq")
            && std::arch::is_x86_feature_detected!("avx512vl");
        #[allow(unexpected_cfgs)]
        let widened = cfg!(multiversion_allow_slow_avx512)
            || (std::arch::is_x86_feature_detected!("avx512bitalg")
                && std::arch::is_x86_feature_detected!("avx512ifma")
                && std::arch::is_x86_feature_detected!("avx512vbmi")
                && std::arch::is_x86_feature_detected!("avx512vbmi2")
                && std::arch::is_x86_feature_detected!("avx512vnni")
                && std::arch::is_x86_feature_detected!("avx512vpopcntdq")
                && std::arch::is_x86_feature_detected!("gfni")
                && std::arch::is_x86_feature_detected!("vaes")
                && std::arch::is_x86_feature_detected!("vpclmulqdq"));
        base && widened
    }};
}

impl Isa {
    /// Every path, best first.
    pub const ALL: [Isa; 4] = [Isa::Avx512, Isa::Avx2, Isa::Neon, Isa::Portable];

    /// Lower-case name, as `PBGI_ISA` takes it.
    pub fn name(self) -> &'static str {
        match self {
            Isa::Avx512 => "avx512",
            Isa::Avx2 => "avx2",
            Isa::Neon => "neon",
            Isa::Portable => "portable",
        }
    }

    /// Whether this path was compiled for this architecture and the CPU runs it.
    pub fn is_available(self) -> bool {
        match self {
            #[cfg(target_arch = "x86_64")]
            Isa::Avx512 => avx512_detected!(),
            #[cfg(target_arch = "x86_64")]
            Isa::Avx2 => {
                std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
            }
            #[cfg(target_arch = "aarch64")]
            Isa::Neon => std::arch::is_aarch64_feature_detected!("neon"),
            Isa::Portable => true,
            #[allow(unreachable_patterns)]
            _ => false,
        }
    }

    /// The paths this CPU runs, best first (always ends with `Portable`).
    pub fn available() -> Vec<Isa> {
        Isa::ALL.into_iter().filter(|i| i.is_available()).collect()
    }

    /// The best path this CPU runs.
    pub fn best() -> Isa {
        Isa::ALL
            .into_iter()
            .find(|i| i.is_available())
            .unwrap_or(Isa::Portable)
    }

    /// `self` if available, else [`Error::IsaUnavailable`].
    pub fn require(self) -> Result<Isa, Error> {
        if self.is_available() {
            Ok(self)
        } else {
            Err(Error::IsaUnavailable {
                requested: self,
                available: Isa::available(),
            })
        }
    }

    /// The path named by `PBGI_ISA`: `None` when unset, empty or `auto`; an
    /// error when unknown or not runnable here.
    pub fn from_env() -> Result<Option<Isa>, Error> {
        match std::env::var("PBGI_ISA") {
            Ok(v) if v.trim().is_empty() || v.trim().eq_ignore_ascii_case("auto") => Ok(None),
            Ok(v) => Ok(Some(v.parse::<Isa>()?.require()?)),
            Err(_) => Ok(None),
        }
    }
}

impl fmt::Display for Isa {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for Isa {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        let t = s.trim().to_ascii_lowercase();
        let t = match t.as_str() {
            "avx-512" | "avx512f" => "avx512",
            "scalar" | "fallback" | "generic" => "portable",
            other => other,
        };
        Isa::ALL
            .into_iter()
            .find(|i| i.name() == t)
            .ok_or_else(|| Error::UnknownIsa { value: s.to_string() })
    }
}

/// Runs `scheme` over all receivers on the traversal's path.
pub(crate) fn run<S: CutSink>(
    t: &Traversal,
    scheme: Scheme,
    receivers: &[Receiver],
    sink: &mut S,
) -> TraversalStats {
    match t.isa() {
        // SAFETY (each arm): a Traversal only holds an Isa whose features
        // `Isa::is_available` detected on this CPU.
        #[cfg(target_arch = "x86_64")]
        Isa::Avx512 => unsafe { run_avx512(t, scheme, receivers, sink) },
        #[cfg(target_arch = "x86_64")]
        Isa::Avx2 => unsafe { run_avx2(t, scheme, receivers, sink) },
        #[cfg(target_arch = "aarch64")]
        Isa::Neon => unsafe { run_neon(t, scheme, receivers, sink) },
        _ => run_portable(t, scheme, receivers, sink),
    }
}

#[multiversion::target("x86_64+avx512f+avx512bw+avx512cd+avx512dq+avx512vl")]
fn run_avx512<S: CutSink>(
    t: &Traversal,
    scheme: Scheme,
    receivers: &[Receiver],
    sink: &mut S,
) -> TraversalStats {
    run_all(t, scheme, receivers, sink)
}

#[multiversion::target("x86_64+avx2+fma")]
fn run_avx2<S: CutSink>(
    t: &Traversal,
    scheme: Scheme,
    receivers: &[Receiver],
    sink: &mut S,
) -> TraversalStats {
    run_all(t, scheme, receivers, sink)
}

#[multiversion::target("aarch64+neon")]
fn run_neon<S: CutSink>(
    t: &Traversal,
    scheme: Scheme,
    receivers: &[Receiver],
    sink: &mut S,
) -> TraversalStats {
    run_all(t, scheme, receivers, sink)
}

// Kept out of line like the other clones, so each one can be found in the
// machine code (scripts/check-asm.sh).
#[inline(never)]
fn run_portable<S: CutSink>(
    t: &Traversal,
    scheme: Scheme,
    receivers: &[Receiver],
    sink: &mut S,
) -> TraversalStats {
    run_all(t, scheme, receivers, sink)
}

/// The body every clone inlines.
#[inline(always)]
fn run_all<S: CutSink>(
    t: &Traversal,
    scheme: Scheme,
    receivers: &[Receiver],
    sink: &mut S,
) -> TraversalStats {
    let mut stats = TraversalStats {
        receivers: receivers.len() as u64,
        ..Default::default()
    };
    if t.tree.is_empty() {
        return stats;
    }
    let mut scratch = single::PairStack::default();
    match scheme {
        Scheme::Scalar => {
            for (i, r) in receivers.iter().enumerate() {
                stats.node_tests += scalar::traverse(t, &r.lanes(), i, sink);
            }
        }
        Scheme::Single => {
            for (i, r) in receivers.iter().enumerate() {
                scratch.clear();
                scratch.push_node(0);
                single::traverse(t, &r.lanes(), i, &mut scratch, sink, &mut stats);
            }
        }
        Scheme::Packet => {
            for (c, chunk) in receivers.chunks(LANES).enumerate() {
                packet::traverse::<S, false>(t, chunk, c * LANES, &mut scratch, sink, &mut stats);
            }
        }
        Scheme::Hybrid => {
            for (c, chunk) in receivers.chunks(LANES).enumerate() {
                packet::traverse::<S, true>(t, chunk, c * LANES, &mut scratch, sink, &mut stats);
            }
        }
    }
    stats
}
