//! UBX framing (u-blox interface description, "UBX protocol": frame structure and
//! checksum): `0xB5 0x62`, class, id, little-endian 16-bit payload length, payload,
//! 8-bit Fletcher checksum CK_A CK_B over class..payload.
//!
//! The scanner never fails: bytes outside a frame (NMEA, RTCM, noise) are skipped
//! and counted; a frame whose checksum does not match is counted and the scan
//! resynchronises one byte after its sync characters; a last frame cut short by the
//! end of the file is reported as truncated.

/// One checksum-verified frame: where it starts and its payload.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Frame<'a> {
    /// Byte offset of the `0xB5` sync character in the input.
    pub offset: usize,
    pub class: u8,
    pub id: u8,
    pub payload: &'a [u8],
}

/// What the scan found besides the frames.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct ScanStats {
    /// Checksum-verified frames.
    pub frames: usize,
    /// Bytes outside any verified frame (other protocols, garbage, bad frames).
    pub skipped_bytes: usize,
    /// Byte offsets of frames whose checksum did not match.
    pub bad_checksums: Vec<usize>,
    /// Byte offset of a last frame cut short by the end of the input.
    pub truncated_at: Option<usize>,
}

/// Fletcher-8 over `bytes` (UBX: class, id, length, payload).
pub fn checksum(bytes: &[u8]) -> (u8, u8) {
    bytes.iter().fold((0u8, 0u8), |(a, b), &x| {
        let a = a.wrapping_add(x);
        (a, b.wrapping_add(a))
    })
}

/// Every verified frame of `data`, in order, and the scan's findings.
pub fn scan(data: &[u8]) -> (Vec<Frame<'_>>, ScanStats) {
    let mut frames = Vec::new();
    let mut st = ScanStats::default();
    let mut i = 0usize;
    while i < data.len() {
        if data[i] != 0xB5 || data.get(i + 1) != Some(&0x62) {
            // A lone 0xB5 as the very last byte is a frame cut short too.
            if data[i] == 0xB5 && i + 1 == data.len() {
                st.truncated_at = Some(i);
            }
            st.skipped_bytes += 1;
            i += 1;
            continue;
        }
        let Some(head) = data.get(i + 2..i + 6) else {
            st.truncated_at = Some(i);
            st.skipped_bytes += data.len() - i;
            break;
        };
        let len = usize::from(u16::from_le_bytes([head[2], head[3]]));
        let end = i + 6 + len + 2;
        if end > data.len() {
            // Either the file ends inside this frame or the "sync" was payload
            // bytes with a large length: keep scanning, and call it truncated
            // only if nothing verified follows.
            st.truncated_at = Some(i);
            st.skipped_bytes += 1;
            i += 1;
            continue;
        }
        let (a, b) = checksum(&data[i + 2..i + 6 + len]);
        if (a, b) != (data[end - 2], data[end - 1]) {
            st.bad_checksums.push(i);
            st.skipped_bytes += 1;
            i += 1;
            continue;
        }
        frames.push(Frame {
            offset: i,
            class: head[0],
            id: head[1],
            payload: &data[i + 6..i + 6 + len],
        });
        st.frames += 1;
        st.truncated_at = None;
        i = end;
    }
    // A "bad checksum" whose frame would have run past a verified frame that
    // follows is usually sync bytes inside other data; they stay counted.
    (frames, st)
}

/// Little-endian field readers over a payload already checked for length.
pub(crate) fn u16_at(p: &[u8], o: usize) -> u16 {
    u16::from_le_bytes([p[o], p[o + 1]])
}
pub(crate) fn u32_at(p: &[u8], o: usize) -> u32 {
    u32::from_le_bytes([p[o], p[o + 1], p[o + 2], p[o + 3]])
}
pub(crate) fn i32_at(p: &[u8], o: usize) -> i32 {
    u32_at(p, o) as i32
}
pub(crate) fn f32_at(p: &[u8], o: usize) -> f32 {
    f32::from_bits(u32_at(p, o))
}
pub(crate) fn f64_at(p: &[u8], o: usize) -> f64 {
    let mut b = [0u8; 8];
    b.copy_from_slice(&p[o..o + 8]);
    f64::from_le_bytes(b)
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn frame(class: u8, id: u8, payload: &[u8]) -> Vec<u8> {
        let mut f = vec![0xB5, 0x62, class, id];
        f.extend_from_slice(&(payload.len() as u16).to_le_bytes());
        f.extend_from_slice(payload);
        let (a, b) = checksum(&f[2..]);
        f.extend_from_slice(&[a, b]);
        f
    }

    #[test]
    fn resynchronises_after_garbage_and_bad_checksum() {
        let good = frame(0x01, 0x07, &[1, 2, 3]);
        let mut bad = frame(0x02, 0x15, &[9; 5]);
        let n = bad.len();
        bad[n - 1] ^= 0xFF;
        let mut data = b"$GPGGA,junk*00\r\n".to_vec();
        data.extend_from_slice(&good);
        data.extend_from_slice(&bad);
        data.extend_from_slice(&good);
        let (frames, st) = scan(&data);
        assert_eq!(frames.len(), 2);
        assert_eq!(frames[0].offset, 16);
        assert_eq!(frames[1].offset, 16 + good.len() + bad.len());
        assert_eq!(st.bad_checksums, vec![16 + good.len()]);
        assert_eq!(st.truncated_at, None);
        assert_eq!(st.skipped_bytes, 16 + bad.len());
    }

    #[test]
    fn truncated_last_frame() {
        let good = frame(0x01, 0x07, &[1, 2, 3]);
        let mut data = good.clone();
        data.extend_from_slice(&good[..7]);
        let (frames, st) = scan(&data);
        assert_eq!(frames.len(), 1);
        assert_eq!(st.truncated_at, Some(good.len()));
        assert!(st.bad_checksums.is_empty());
    }
}
