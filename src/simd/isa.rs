//! The instruction-set paths of the kernels, their detection on this CPU and
//! the `PBGI_ISA` override. A platform concept: it knows nothing of the
//! kernels it selects between.

use std::fmt;
use std::str::FromStr;

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

    /// `self` if available, else [`IsaError::Unavailable`].
    pub fn require(self) -> Result<Isa, IsaError> {
        if self.is_available() {
            Ok(self)
        } else {
            Err(IsaError::Unavailable {
                requested: self,
                available: Isa::available(),
            })
        }
    }

    /// The path named by `PBGI_ISA`: `None` when unset, empty or `auto`; an
    /// error when unknown or not runnable here.
    pub fn from_env() -> Result<Option<Isa>, IsaError> {
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
    type Err = IsaError;
    fn from_str(s: &str) -> Result<Self, IsaError> {
        let t = s.trim().to_ascii_lowercase();
        let t = match t.as_str() {
            "avx-512" | "avx512f" => "avx512",
            "scalar" | "fallback" | "generic" => "portable",
            other => other,
        };
        Isa::ALL
            .into_iter()
            .find(|i| i.name() == t)
            .ok_or_else(|| IsaError::Unknown { value: s.to_string() })
    }
}

/// Errors of choosing an instruction-set path.
#[derive(Clone, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum IsaError {
    /// The requested path cannot run on this CPU (or was not compiled for
    /// this architecture).
    Unavailable {
        /// The path asked for.
        requested: Isa,
        /// The paths this CPU can run, best first.
        available: Vec<Isa>,
    },
    /// `PBGI_ISA` or a parsed name is not a known path.
    Unknown {
        /// The text given.
        value: String,
    },
}

impl fmt::Display for IsaError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            IsaError::Unavailable { requested, available } => {
                let names: Vec<_> = available.iter().map(|i| i.name()).collect();
                write!(
                    f,
                    "instruction set {} is not available on this CPU (available: {})",
                    requested.name(),
                    names.join(", ")
                )
            }
            IsaError::Unknown { value } => write!(
                f,
                "unknown instruction set {value:?} (expected auto, avx512, avx2, neon or portable)"
            ),
        }
    }
}

impl std::error::Error for IsaError {}
