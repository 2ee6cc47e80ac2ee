/// The digest the generated file records of the description it was generated from:
/// 64-bit FNV-1a of its bytes, in hex. The firmware's build script computes it again (it
/// includes this file), so that a description changed since generation stops the build.
pub fn digest(bytes: &[u8]) -> String {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0000_0100_0000_01b3);
    }
    format!("{h:016x}")
}
