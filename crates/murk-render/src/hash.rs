//! FNV-1a, 64 bits: the one hash behind render keys' short names, the surface and density
//! fingerprints in a scene's key and a checkpoint record's checksum. A leaf module, so that geometry,
//! media and the renderer all use it without importing one another. Its values are stored in file
//! names and checkpoints, so they never change.
//!
//! ```
//! use murk_render::hash::{fnv1a, Fnv1a};
//! assert_eq!(fnv1a(*b"a"), 0xaf63_dc4c_8601_ec8c); // the published FNV-1a test vector
//! assert_eq!(Fnv1a::new().word(u64::from(b'a')).finish(), fnv1a(*b"a"));
//! ```

/// A running FNV-1a state, fed one word at a time (a byte is a word below 256).
#[derive(Clone, Copy, Debug)]
pub struct Fnv1a(u64);

impl Fnv1a {
    const OFFSET_BASIS: u64 = 0xcbf2_9ce4_8422_2325;
    const PRIME: u64 = 0x0100_0000_01b3;

    /// The standard starting state.
    pub const fn new() -> Self {
        Fnv1a(Self::OFFSET_BASIS)
    }

    /// A state that starts from `basis` instead of the standard offset basis (a seed per name).
    pub const fn with_basis(basis: u64) -> Self {
        Fnv1a(basis)
    }

    /// The state after `w`: xor, then multiply by the FNV prime. Bytes as words give FNV-1a proper;
    /// 8-byte words take one multiply per eight bytes, which keeps long buffers cheap to hash.
    #[inline]
    pub const fn word(self, w: u64) -> Self {
        Fnv1a((self.0 ^ w).wrapping_mul(Self::PRIME))
    }

    /// The hash so far.
    pub const fn finish(self) -> u64 {
        self.0
    }
}

impl Default for Fnv1a {
    fn default() -> Self {
        Self::new()
    }
}

/// FNV-1a, 64 bits, of `bytes`.
#[inline]
pub fn fnv1a(bytes: impl IntoIterator<Item = u8>) -> u64 {
    bytes
        .into_iter()
        .fold(Fnv1a::new(), |h, b| h.word(u64::from(b)))
        .finish()
}
