//! What a JPEG says of itself in its marker segments before the scan (ITU T.81 B.1): a walk
//! over those segments, and the chroma subsampling its frame header gives. Its own file so that
//! `meta` (the subsampling) and `resolution` (the JFIF density) share the walk without
//! importing each other.

/// A JPEG's chroma subsampling: its luma sampling factors over its chroma's, (2, 2) for
/// 4:2:0, (2, 1) for 4:2:2, (1, 1) for 4:4:4; `None` for a grey or CMYK JPEG, or chroma
/// sampled unlike the usual forms (both chroma components at 1×1).
pub fn sampling(bytes: &[u8]) -> Option<(u8, u8)> {
    segment(bytes, |marker, body| {
        // Start of frame: every SOFn but DHT (C4), JPG (C8) and DAC (CC).
        if !matches!(marker, 0xC0..=0xCF) || matches!(marker, 0xC4 | 0xC8 | 0xCC) {
            return None;
        }
        if body.get(5) != Some(&3) {
            return Some(None);
        }
        let factors = |c: usize| {
            let hv = *body.get(6 + 3 * c + 1)?;
            Some((hv >> 4, hv & 0x0F))
        };
        let found = (|| Some((factors(0)?, factors(1)?, factors(2)?)))();
        Some(found.and_then(|(luma, cb, cr)| (cb == (1, 1) && cr == (1, 1)).then_some(luma)))
    })
    .flatten()
}

/// Walks a JPEG's marker segments up to the start of scan, giving `pick` each one's marker and
/// body (after its length): the first `Some` it answers ends the walk. `None` where no segment
/// is picked, or the bytes end or break off first.
pub(super) fn segment<T>(bytes: &[u8], mut pick: impl FnMut(u8, &[u8]) -> Option<T>) -> Option<T> {
    let mut at = 2;
    loop {
        while bytes.get(at) == Some(&0xFF) && bytes.get(at + 1) == Some(&0xFF) {
            at += 1;
        }
        if *bytes.get(at)? != 0xFF {
            return None;
        }
        let marker = *bytes.get(at + 1)?;
        at += 2;
        match marker {
            0x01 | 0xD0..=0xD7 => continue,
            0xD9 | 0xDA => return None,
            _ => {}
        }
        let length = u16::from_be_bytes([*bytes.get(at)?, *bytes.get(at + 1)?]) as usize;
        if let Some(found) = pick(marker, bytes.get(at + 2..at + length)?) {
            return Some(found);
        }
        at += length;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jpeg_sampling_reads_the_frame_header() {
        // SOI, SOF0 of 3 components: Y 2×2, Cb 1×1, Cr 1×1 (4:2:0).
        let mut jpeg = vec![0xFF, 0xD8, 0xFF, 0xC0, 0, 17, 8, 0, 16, 0, 16, 3];
        jpeg.extend([1, 0x22, 0, 2, 0x11, 1, 3, 0x11, 1]);
        assert_eq!(sampling(&jpeg), Some((2, 2)));
        jpeg[13] = 0x21;
        assert_eq!(sampling(&jpeg), Some((2, 1)));
    }
}
