//! The one dispatch point: every kernel entry (the traversal, the scalar and
//! the 16-lane shading pipelines) is a [`Kernel`], compiled here into one
//! clone per instruction set with `multiversion::target` and entered by
//! [`dispatch`] on the path it is given, in the spirit of pulp's `WithSimd`.
//!
//! A kernel's [`run`](Kernel::run) and everything it calls must be
//! `#[inline(always)]` (closures too), so that each clone compiles the whole
//! body with its own target features; `scripts/check-asm.sh` checks the
//! machine code of every clone for that.

use super::isa::Isa;

/// A kernel body, run by [`dispatch`] inside the clone of one instruction
/// set. Implement [`run`](Kernel::run) with `#[inline(always)]`.
pub(crate) trait Kernel {
    /// What the kernel returns.
    type Output;
    /// The body.
    fn run(self) -> Self::Output;
}

/// Runs `kernel` in the clone compiled for `isa`.
///
/// Panics if the CPU does not run `isa` (entering that clone would execute
/// instructions the CPU lacks): callers obtain `isa` from detection
/// ([`Isa::require`], [`Isa::best`]), so this is a check, not a path.
#[inline(always)]
pub(crate) fn dispatch<K: Kernel>(isa: Isa, kernel: K) -> K::Output {
    assert!(
        isa.is_available(),
        "instruction set {isa} is not available on this CPU"
    );
    match isa {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the assertion above detected AVX-512 (the clone's features,
        // as `Isa::is_available` lists them) on this CPU.
        Isa::Avx512 => unsafe { avx512(kernel) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the assertion above detected AVX2 and FMA on this CPU.
        Isa::Avx2 => unsafe { avx2(kernel) },
        #[cfg(target_arch = "aarch64")]
        // SAFETY: the assertion above detected NEON on this CPU.
        Isa::Neon => unsafe { neon(kernel) },
        _ => portable(kernel),
    }
}

// The feature sets: `Isa::is_available` detects exactly these (multiversion
// widens an AVX-512 target to the Ice Lake extensions, which it checks too).

#[multiversion::target("x86_64+avx512f+avx512bw+avx512cd+avx512dq+avx512vl")]
fn avx512<K: Kernel>(kernel: K) -> K::Output {
    kernel.run()
}

#[multiversion::target("x86_64+avx2+fma")]
fn avx2<K: Kernel>(kernel: K) -> K::Output {
    kernel.run()
}

#[multiversion::target("aarch64+neon")]
fn neon<K: Kernel>(kernel: K) -> K::Output {
    kernel.run()
}

// Kept out of line like the other clones, so each one can be found in the
// machine code (scripts/check-asm.sh).
#[inline(never)]
fn portable<K: Kernel>(kernel: K) -> K::Output {
    kernel.run()
}
