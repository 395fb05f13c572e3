//! GenoM3's C data that holds a pointer, owned on the Rust side: an unbounded
//! `sequence<T>` ([`Sequence`], GenoM3's struct of `_maximum`, `_length`, `_buffer` and
//! `_release`) and an unbounded `string` ([`GenomString`], a `char *`), each of its C
//! layout, so that the glue's memory holds them where the codels expect them.
//!
//! Ownership follows GenoM3's C mapping, so that a codel's `genom_sequence_reserve`, its
//! `free` and its `malloc` agree with the engine's: a sequence's buffer is released by
//! its `_release` (none: not owned, left alone), after the first `_length` elements are
//! dropped; a string is a `malloc`ed, NUL-terminated buffer that `free` releases (NULL is
//! none). A clone is deep, in buffers from `malloc` (`_release` is `free`), so that the
//! engine's copy of port data or of a reply outlives the codels' own.

use core::ffi::{c_char, c_void, CStr};
use core::ptr;

extern "C" {
    fn malloc(size: usize) -> *mut c_void;
    fn free(p: *mut c_void);
}

/// What releases a buffer: `free`, as `genom_sequence_reserve` sets it.
pub type Release = Option<unsafe extern "C" fn(*mut c_void)>;

/// `n` elements of `T` from `malloc`; null for none (and if `malloc` fails, which the
/// caller treats as out of memory).
fn alloc<T>(n: usize) -> *mut T {
    if n == 0 {
        return ptr::null_mut();
    }
    let bytes = n.checked_mul(core::mem::size_of::<T>().max(1));
    // SAFETY: malloc of a size; null on failure, checked by the caller
    let p = bytes.map_or(ptr::null_mut(), |b| unsafe { malloc(b) });
    if p.is_null() {
        std::alloc::handle_alloc_error(std::alloc::Layout::new::<T>());
    }
    p.cast()
}

/// GenoM3's unbounded `sequence<T>`: `_length` elements in a buffer of room for
/// `_maximum`, released by `_release`. All zero is the empty sequence.
#[repr(C)]
pub struct Sequence<T> {
    pub _maximum: u32,
    pub _length: u32,
    pub _buffer: *mut T,
    pub _release: Release,
}

// SAFETY: a sequence owns its buffer and elements; the codels touch it only during a
// call the engine makes, one at a time
unsafe impl<T: Send> Send for Sequence<T> {}
unsafe impl<T: Sync> Sync for Sequence<T> {}

impl<T> Default for Sequence<T> {
    fn default() -> Self {
        Sequence {
            _maximum: 0,
            _length: 0,
            _buffer: ptr::null_mut(),
            _release: None,
        }
    }
}

impl<T> Sequence<T> {
    /// Its `_length` elements (none while `_buffer` is null).
    pub fn as_slice(&self) -> &[T] {
        if self._buffer.is_null() {
            return &[];
        }
        // SAFETY: the first `_length` elements of the buffer are valid (GenoM3's invariant,
        // which the codels keep)
        unsafe { core::slice::from_raw_parts(self._buffer, self._length as usize) }
    }

    /// Its elements, to change in place.
    pub fn as_mut_slice(&mut self) -> &mut [T] {
        if self._buffer.is_null() {
            return &mut [];
        }
        // SAFETY: as in `as_slice`, and `self` is borrowed mutably
        unsafe { core::slice::from_raw_parts_mut(self._buffer, self._length as usize) }
    }

    pub fn len(&self) -> usize {
        self.as_slice().len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// A sequence of `items`, in a buffer from `malloc`; more than `u32::MAX` items are
    /// cut there (GenoM3's `_length` is a `uint32_t`).
    pub fn from_vec(items: Vec<T>) -> Self {
        let n = items.len().min(u32::MAX as usize);
        let buffer = alloc::<T>(n);
        for (k, item) in items.into_iter().take(n).enumerate() {
            // SAFETY: `buffer` has room for `n` elements, each written once
            unsafe { buffer.add(k).write(item) };
        }
        Sequence {
            _maximum: n as u32,
            _length: n as u32,
            _buffer: buffer,
            _release: Some(free),
        }
    }
}

impl<T: Clone> Sequence<T> {
    pub fn from_slice(items: &[T]) -> Self {
        Sequence::from_vec(items.to_vec())
    }

    pub fn to_vec(&self) -> Vec<T> {
        self.as_slice().to_vec()
    }
}

impl<T: Clone> Clone for Sequence<T> {
    fn clone(&self) -> Self {
        Sequence::from_slice(self.as_slice())
    }
}

impl<T> Drop for Sequence<T> {
    fn drop(&mut self) {
        if self._buffer.is_null() {
            return;
        }
        // SAFETY: the first `_length` elements are valid and owned; the buffer is the
        // release function's to free
        unsafe {
            ptr::drop_in_place(self.as_mut_slice() as *mut [T]);
            if let Some(release) = self._release {
                release(self._buffer.cast());
            }
        }
        self._buffer = ptr::null_mut();
    }
}

impl<T: core::fmt::Debug> core::fmt::Debug for Sequence<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_list().entries(self.as_slice()).finish()
    }
}

impl<T: PartialEq> PartialEq for Sequence<T> {
    fn eq(&self, other: &Self) -> bool {
        self.as_slice() == other.as_slice()
    }
}

/// GenoM3's unbounded `string`: a `char *` to a `malloc`ed, NUL-terminated buffer, or
/// null, which is no string (read as empty).
#[repr(transparent)]
pub struct GenomString(pub *mut c_char);

// SAFETY: the string owns its buffer, which the codels touch only during a call
unsafe impl Send for GenomString {}
unsafe impl Sync for GenomString {}

impl Default for GenomString {
    fn default() -> Self {
        GenomString(ptr::null_mut())
    }
}

impl GenomString {
    /// A copy of `text` in a buffer from `malloc`, cut at its first NUL (C's end).
    pub fn new(text: &str) -> Self {
        let bytes = text.as_bytes();
        let n = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
        GenomString::of_bytes(&bytes[..n])
    }

    /// `bytes` (holding no NUL) and a NUL after them, from `malloc`.
    fn of_bytes(bytes: &[u8]) -> Self {
        let p = alloc::<u8>(bytes.len() + 1);
        // SAFETY: `p` has room for the bytes and the NUL
        unsafe {
            ptr::copy_nonoverlapping(bytes.as_ptr(), p, bytes.len());
            p.add(bytes.len()).write(0);
        }
        GenomString(p.cast())
    }

    /// Its text as C holds it; `None` while null.
    pub fn as_c_str(&self) -> Option<&CStr> {
        // SAFETY: a non-null string is NUL-terminated (the codels' contract)
        (!self.0.is_null()).then(|| unsafe { CStr::from_ptr(self.0) })
    }

    /// Its text, bytes that are not UTF-8 replaced; empty while null.
    pub fn to_string_lossy(&self) -> String {
        self.as_c_str()
            .map_or_else(String::new, |s| s.to_string_lossy().into_owned())
    }
}

impl Clone for GenomString {
    fn clone(&self) -> Self {
        match self.as_c_str() {
            Some(s) => GenomString::of_bytes(s.to_bytes()),
            None => GenomString::default(),
        }
    }
}

impl Drop for GenomString {
    fn drop(&mut self) {
        if !self.0.is_null() {
            // SAFETY: a non-null string is from malloc and owned here
            unsafe { free(self.0.cast()) };
            self.0 = ptr::null_mut();
        }
    }
}

impl core::fmt::Debug for GenomString {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self.as_c_str() {
            Some(s) => core::fmt::Debug::fmt(s, f),
            None => f.write_str("NULL"),
        }
    }
}

impl PartialEq for GenomString {
    fn eq(&self, other: &Self) -> bool {
        self.as_c_str() == other.as_c_str()
    }
}

/// GenoM3's bounded `string<N>` (`char[N]`) holding `text`, cut at its first NUL and to
/// `N - 1` bytes, NUL after.
pub fn bounded_string<const N: usize>(text: &str) -> [c_char; N] {
    let mut out = [0; N];
    let bytes = text.as_bytes();
    let n = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    for (o, &b) in out.iter_mut().zip(&bytes[..n.min(N.saturating_sub(1))]) {
        *o = b as c_char;
    }
    out
}

/// The text of a bounded string, up to its first NUL (all of it without one), bytes that
/// are not UTF-8 replaced.
pub fn bounded_text(chars: &[c_char]) -> String {
    let bytes: Vec<u8> = chars
        .iter()
        .take_while(|&&c| c != 0)
        .map(|&c| c as u8)
        .collect();
    String::from_utf8_lossy(&bytes).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_sequence_clones_deeply_and_drops_its_elements() {
        let names = Sequence::from_vec(vec![GenomString::new("left"), GenomString::new("right")]);
        let copy = names.clone();
        assert_ne!(names._buffer, copy._buffer);
        assert_ne!(names.as_slice()[0].0, copy.as_slice()[0].0);
        assert_eq!(copy.as_slice()[1].to_string_lossy(), "right");
        drop(names);
        assert_eq!(copy.as_slice()[0].to_string_lossy(), "left");
        assert_eq!((copy._length, copy._maximum), (2, 2));
    }

    #[test]
    fn empty_and_null_read_as_empty() {
        let s: Sequence<u8> = Sequence::default();
        assert!(s.as_slice().is_empty());
        assert!(s.clone()._buffer.is_null());
        assert_eq!(GenomString::default().to_string_lossy(), "");
        assert_eq!(GenomString::default().clone(), GenomString::default());
    }

    #[test]
    fn a_string_ends_at_its_first_nul() {
        let s = GenomString::new("cam\0era");
        assert_eq!(s.to_string_lossy(), "cam");
        assert_eq!(s.clone().as_c_str().map(CStr::to_bytes), Some(&b"cam"[..]));
    }

    #[test]
    fn a_bounded_string_keeps_room_for_its_nul() {
        let s: [c_char; 4] = bounded_string("camera");
        assert_eq!(bounded_text(&s), "cam");
        assert_eq!(bounded_text(&bounded_string::<8>("a\0b")), "a");
        assert_eq!(bounded_text(&[b'x' as c_char; 2]), "xx");
    }

    #[test]
    fn a_buffer_without_release_is_not_freed() {
        let mut kept = [1u8, 2, 3];
        let s = Sequence {
            _maximum: 3,
            _length: 3,
            _buffer: kept.as_mut_ptr(),
            _release: None,
        };
        assert_eq!(s.to_vec(), vec![1, 2, 3]);
        drop(s);
        assert_eq!(kept, [1, 2, 3]);
    }
}
