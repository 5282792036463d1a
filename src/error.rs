//! Typed errors of the kernel layer: each names the offending item.

use std::fmt;

use crate::simd::IsaError;

/// What is wrong with one input value.
#[derive(Clone, Debug, PartialEq)]
pub enum Invalid {
    /// A component is NaN or infinite.
    NonFinite {
        /// The field holding it (`"position"`, `"normal"`, `"radius"`, `"radiance"`).
        field: &'static str,
    },
    /// The radius is zero or negative.
    NonPositiveRadius(f32),
    /// A radiance component is negative.
    NegativeRadiance,
    /// A value beyond the supported range: a position component or the radius
    /// beyond [`MAX_COORDINATE`](crate::points::MAX_COORDINATE), a radiance
    /// component beyond [`MAX_RADIANCE`](crate::points::MAX_RADIANCE).
    TooLarge {
        /// The field holding it (`"position"`, `"radius"`, `"radiance"`).
        field: &'static str,
        /// The largest offending value (absolute value for a position).
        value: f32,
        /// The most accepted.
        max: f32,
    },
    /// The normal has length zero.
    ZeroNormal,
    /// The normal is not of unit length (within [`NORMAL_TOLERANCE`]).
    NonUnitNormal {
        /// Its length.
        length: f32,
    },
    /// Another direction (a glossy receiver's outgoing direction) is zero or
    /// not of unit length within [`NORMAL_SLACK`](crate::gather::NORMAL_SLACK).
    NonUnitDirection {
        /// The field holding it.
        field: &'static str,
        /// Its length.
        length: f32,
    },
}

/// Largest accepted `|length² − 1|` of a normal. Normals are never renormalized
/// behind the caller's back, so one a little off is rejected instead.
pub const NORMAL_TOLERANCE: f32 = 1e-4;

/// Errors of the kernel layer (point cloud, receivers, traversal options, dispatch).
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum Error {
    /// Surfel `index` of the input is invalid.
    InvalidSurfel {
        /// Position of the surfel in the caller's input.
        index: usize,
        /// What is wrong with it.
        reason: Invalid,
    },
    /// A receiver is invalid (`index` is its position in the caller's input,
    /// or 0 for one built alone).
    InvalidReceiver {
        /// Position of the receiver in the caller's input.
        index: usize,
        /// What is wrong with it.
        reason: Invalid,
    },
    /// A traversal parameter is out of range.
    InvalidParameter {
        /// Parameter name.
        name: &'static str,
        /// The value given, as text.
        value: String,
        /// What is accepted.
        expected: &'static str,
    },
    /// More surfels than node indices can address.
    TooManySurfels {
        /// Surfels given.
        count: usize,
        /// The most accepted.
        max: usize,
    },
    /// The instruction-set path asked for is unknown or cannot run here.
    Isa(IsaError),
    /// A scheme name is not known.
    UnknownScheme {
        /// The text given.
        value: String,
    },
    /// A texel of an environment map (its index, row by row), or a uniform
    /// sky's radiance (index 0), is invalid.
    InvalidEnvironment {
        /// The texel.
        index: usize,
        /// What is wrong with it.
        reason: Invalid,
    },
    /// More receivers (or microbuffers) than one call takes: a
    /// [`PacketCut`](crate::microbuffer::PacketCut) and
    /// [`shade_packet`](crate::microbuffer::shade_packet) hold one packet.
    TooManyReceivers {
        /// Receivers given.
        given: usize,
        /// The most taken.
        most: usize,
    },
}

impl fmt::Display for Invalid {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Invalid::NonFinite { field } => write!(f, "{field} is not finite"),
            Invalid::NonPositiveRadius(r) => write!(f, "radius {r} is not positive"),
            Invalid::NegativeRadiance => write!(f, "radiance has a negative component"),
            Invalid::TooLarge { field, value, max } => write!(f, "{field} {value:e} exceeds {max:e}"),
            Invalid::ZeroNormal => write!(f, "normal has zero length"),
            Invalid::NonUnitNormal { length } => {
                write!(f, "normal has length {length}, expected 1")
            }
            Invalid::NonUnitDirection { field, length } => {
                write!(f, "{field} has length {length}, expected 1")
            }
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::InvalidSurfel { index, reason } => write!(f, "surfel {index}: {reason}"),
            Error::InvalidReceiver { index, reason } => write!(f, "receiver {index}: {reason}"),
            Error::InvalidParameter {
                name,
                value,
                expected,
            } => write!(f, "parameter {name} = {value}: expected {expected}"),
            Error::TooManySurfels { count, max } => {
                write!(f, "{count} surfels given, at most {max} supported")
            }
            Error::Isa(e) => e.fmt(f),
            Error::UnknownScheme { value } => write!(
                f,
                "unknown traversal scheme {value:?} (expected scalar, single, packet or hybrid)"
            ),
            Error::InvalidEnvironment { index, reason } => write!(f, "environment texel {index}: {reason}"),
            Error::TooManyReceivers { given, most } => {
                write!(
                    f,
                    "{given} receivers for one call that takes at most {most} (one packet)"
                )
            }
        }
    }
}

impl std::error::Error for Error {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        match self {
            Error::Isa(e) => Some(e),
            _ => None,
        }
    }
}

impl From<IsaError> for Error {
    fn from(e: IsaError) -> Self {
        Error::Isa(e)
    }
}
