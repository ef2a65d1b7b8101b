//! Feed arbitrary bytes, in arbitrary chunk sizes, to the streaming decoder of
//! both protocols: it must never panic, never hold more than its fixed buffer, and
//! return only frames whose checksum holds.
#![no_main]

use libfuzzer_sys::fuzz_target;
use twinloop_link::{Accept, Decoder, Protocol, checksum_v1, crc16};

fuzz_target!(|data: &[u8]| {
    let Some((&first, bytes)) = data.split_first() else {
        return;
    };
    let accept = match first % 3 {
        0 => Accept::V1,
        1 => Accept::V2,
        _ => Accept::Both,
    };
    let chunk = 1 + (first as usize >> 2);
    let mut d = Decoder::with_max_packet(accept, 300);
    let mut rest = bytes;
    while !rest.is_empty() {
        let n = d.push(&rest[..chunk.min(rest.len())]);
        rest = &rest[n..];
        assert!(d.buffered() <= 600);
        while let Some(f) = d.next_frame() {
            let raw = f.raw;
            let n = raw.len();
            assert!(n <= 300);
            match f.protocol {
                Protocol::V1 => assert_eq!(checksum_v1(&raw[2..n - 1]), raw[n - 1]),
                Protocol::V2 => assert_eq!(
                    crc16(&raw[..n - 2]),
                    u16::from_le_bytes([raw[n - 2], raw[n - 1]])
                ),
            }
        }
    }
    while d.next_frame_flushing().is_some() {}
    assert_eq!(d.buffered(), 0);
});
