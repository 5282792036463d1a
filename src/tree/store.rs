//! One of a compact tree's arrays: owned, as the build makes it, or a
//! slice of a mapped tree file (feature `mmap`), as the file holds it.
//!
//! A mapped slice is sound because:
//! * its element types are [`Plain`]: `repr(C)` structs of integers and
//!   floats, for which every bit pattern is a value (their padding is never
//!   read as one);
//! * the reader maps only on a little-endian machine, the file's order, and
//!   only sections that start on a multiple of their type's alignment
//!   (each starts on a multiple of 64 bytes, the map on a page);
//! * the reader checks every byte the kernels read before the tree is
//!   used, as the copying reader does, and the bytes cannot change after
//!   that: pbgi writes a tree file to a new name and renames it over the
//!   old one, so a mapped file is never written again in place. A file
//!   written in place by another program while mapped is outside what the
//!   map can guard against (the `unsafe` of [`memmap2::Mmap::map`]).

use std::ops::Deref;

/// A type whose every bit pattern is a value, laid out by `repr(C)` with
/// its fields little-endian in a tree file.
///
/// # Safety
/// Implement only for `repr(C)` structs of integers and floats (and arrays
/// of them), whose file form is their memory image on a little-endian
/// machine.
pub(crate) unsafe trait Plain: Copy {}

/// An owned array, or a checked slice of a mapped file.
#[derive(Clone, Debug)]
pub(crate) enum Store<T> {
    Owned(Vec<T>),
    #[cfg(feature = "mmap")]
    Mapped(Mapped<T>),
}

impl<T> Default for Store<T> {
    fn default() -> Self {
        Store::Owned(Vec::new())
    }
}

impl<T> From<Vec<T>> for Store<T> {
    fn from(v: Vec<T>) -> Self {
        Store::Owned(v)
    }
}

impl<T> Deref for Store<T> {
    type Target = [T];

    #[inline(always)]
    fn deref(&self) -> &[T] {
        match self {
            Store::Owned(v) => v,
            #[cfg(feature = "mmap")]
            Store::Mapped(m) => m.slice(),
        }
    }
}

impl<T> Store<T> {
    /// The owned array, to write in place: the build's, never a mapped one.
    pub fn owned_mut(&mut self) -> &mut [T] {
        match self {
            Store::Owned(v) => v,
            #[cfg(feature = "mmap")]
            Store::Mapped(_) => {
                unreachable!("only a built tree is written, and a built tree owns its arrays")
            }
        }
    }

    /// Whether the array lies in a mapped file.
    pub fn is_mapped(&self) -> bool {
        !matches!(self, Store::Owned(_))
    }
}

/// A mapped tree file (nothing without the `mmap` feature).
#[cfg(feature = "mmap")]
pub(crate) type Map = std::sync::Arc<memmap2::Mmap>;
/// A mapped tree file (nothing without the `mmap` feature).
#[cfg(not(feature = "mmap"))]
pub(crate) enum Map {}

impl<T: Plain> Store<T> {
    /// `len` values from byte `at` of `map` where they can be used in
    /// place (see [`Mapped::new`]), else the values `read` gives.
    pub fn take(map: Option<&Map>, at: usize, len: usize, read: impl FnOnce() -> Vec<T>) -> Store<T> {
        #[cfg(feature = "mmap")]
        if let Some(m) = map.and_then(|m| Mapped::new(m, at, len)) {
            return Store::Mapped(m);
        }
        #[cfg(not(feature = "mmap"))]
        let _ = (map.map(|m| match *m {}), at, len);
        Store::Owned(read())
    }
}

/// `len` values of `T` from byte `at` of a mapped file.
#[cfg(feature = "mmap")]
pub(crate) struct Mapped<T> {
    map: Map,
    at: usize,
    len: usize,
    _values: std::marker::PhantomData<T>,
}

#[cfg(feature = "mmap")]
impl<T> Clone for Mapped<T> {
    fn clone(&self) -> Self {
        Mapped {
            map: Map::clone(&self.map),
            at: self.at,
            len: self.len,
            _values: std::marker::PhantomData,
        }
    }
}

#[cfg(feature = "mmap")]
impl<T> std::fmt::Debug for Mapped<T> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Mapped {{ at: {}, len: {} }}", self.at, self.len)
    }
}

#[cfg(feature = "mmap")]
impl<T: Plain> Mapped<T> {
    /// `len` values from byte `at` of `map`; `None` where they would not
    /// lie in the map, aligned, or the machine is not little-endian.
    pub fn new(map: &Map, at: usize, len: usize) -> Option<Mapped<T>> {
        let bytes = len.checked_mul(size_of::<T>())?;
        let fits = at.checked_add(bytes).is_some_and(|end| end <= map.len());
        let aligned = (map.as_ptr() as usize + at).is_multiple_of(align_of::<T>());
        (cfg!(target_endian = "little") && fits && aligned).then(|| Mapped {
            map: Map::clone(map),
            at,
            len,
            _values: std::marker::PhantomData,
        })
    }
}

#[cfg(feature = "mmap")]
impl<T> Mapped<T> {
    #[inline(always)]
    pub fn slice(&self) -> &[T] {
        // SAFETY: `new` checked that the values lie in the map and are
        // aligned, and `T: Plain` makes any bytes a value; the map lives
        // as long as `self` (the `Arc`), and its bytes do not change
        // (see the module's notes).
        unsafe { std::slice::from_raw_parts(self.map.as_ptr().add(self.at).cast::<T>(), self.len) }
    }
}
