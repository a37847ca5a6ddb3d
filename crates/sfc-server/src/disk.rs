//! Chart files on disk: the content hash that detects changes made outside the editor. Writes
//! that never leave a partial file are the driver's (`sfc_driver::write_atomically`), shared
//! with the command line.

pub(crate) use sfc_driver::write_atomically;

/// The hash `open` and `save` return: FNV-1a (64 bits) of the file's bytes, 16 hex digits.
/// Only compared for equality, so a fast stable hash is enough.
pub fn content_hash(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in bytes {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hash_is_fnv1a() {
        // Reference values of FNV-1a 64.
        assert_eq!(content_hash(b""), "cbf29ce484222325");
        assert_eq!(content_hash(b"a"), "af63dc4c8601ec8c");
        assert_eq!(content_hash(b"foobar"), "85944171f73967e8");
    }
}
