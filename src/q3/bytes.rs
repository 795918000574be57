//! Little-endian readers over byte slices, shared by the binary loaders (IBSP maps, MD3 models).
//!
//! Callers check their bounds first (lump and record sizes, MD3 regions); a read that would still
//! run past the slice gives zeros (an empty name) instead of panicking, so the readers are
//! panic-free whatever they are handed.

/// The `N` bytes at `at`; zeros when they are not all inside `b`.
pub fn array_at<const N: usize>(b: &[u8], at: usize) -> [u8; N] {
    let mut out = [0u8; N];
    if let Some(s) = at.checked_add(N).and_then(|end| b.get(at..end)) {
        out.copy_from_slice(s);
    }
    out
}

pub fn i16_at(b: &[u8], at: usize) -> i16 {
    i16::from_le_bytes(array_at(b, at))
}

pub fn u16_at(b: &[u8], at: usize) -> u16 {
    u16::from_le_bytes(array_at(b, at))
}

pub fn i32_at(b: &[u8], at: usize) -> i32 {
    i32::from_le_bytes(array_at(b, at))
}

pub fn f32_at(b: &[u8], at: usize) -> f32 {
    f32::from_le_bytes(array_at(b, at))
}

/// Three consecutive `f32`s.
pub fn vec3_at(b: &[u8], at: usize) -> [f32; 3] {
    [f32_at(b, at), f32_at(b, at + 4), f32_at(b, at + 8)]
}

/// Three consecutive `i32`s.
pub fn ivec3_at(b: &[u8], at: usize) -> [i32; 3] {
    [i32_at(b, at), i32_at(b, at + 4), i32_at(b, at + 8)]
}

/// A fixed-size, NUL-terminated name field of `len` bytes, as lossy UTF-8 (the whole field when
/// it holds no NUL; empty when it is not inside `b`).
pub fn name_at(b: &[u8], at: usize, len: usize) -> String {
    let raw = at
        .checked_add(len)
        .and_then(|end| b.get(at..end))
        .unwrap_or(&[]);
    let end = raw.iter().position(|&c| c == 0).unwrap_or(raw.len());
    String::from_utf8_lossy(&raw[..end]).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn integers_are_little_endian() {
        let b = [0xff, 0x78, 0x56, 0x34, 0x12, 0xfe, 0xff];
        assert_eq!(i32_at(&b, 1), 0x1234_5678);
        assert_eq!(u16_at(&b, 1), 0x5678);
        assert_eq!(i16_at(&b, 5), -2);
        assert_eq!(i32_at(&(-3i32).to_le_bytes(), 0), -3);
        assert_eq!(
            ivec3_at(&[1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0], 0),
            [1, 256, 65536]
        );
    }

    #[test]
    fn floats_are_little_endian() {
        // 1.0f32 is 0x3f800000: big-endian reading of these bytes would give a denormal.
        let b = [0x00, 0x00, 0x00, 0x80, 0x3f];
        assert_eq!(f32_at(&b, 1), 1.0);
        let v: Vec<u8> = [1.5f32, -2.0, 1e6]
            .iter()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        assert_eq!(vec3_at(&v, 0), [1.5, -2.0, 1e6]);
    }

    #[test]
    fn names_stop_at_the_first_nul() {
        let mut field = [0u8; 8];
        field[..3].copy_from_slice(b"abc");
        field[4] = b'x';
        assert_eq!(name_at(&field, 0, 8), "abc");
        assert_eq!(name_at(b"..fullname", 2, 8), "fullname");
        assert_eq!(name_at(&[b'a', 0xff, 0], 0, 3), "a\u{fffd}");
    }

    #[test]
    fn reads_outside_the_slice_give_zeros_not_panics() {
        let b = [1u8, 2, 3];
        assert_eq!(i32_at(&b, 0), 0);
        assert_eq!(f32_at(&b, usize::MAX - 1), 0.0);
        assert_eq!(array_at::<2>(&b, 2), [0, 0]);
        assert_eq!(name_at(&b, 1, 5), "");
        assert_eq!(name_at(&b, usize::MAX, 2), "");
    }
}
