//! Property tests of the streaming decoder over random byte streams: it never
//! panics, never holds more than its fixed buffer whatever a LENGTH field says,
//! returns only packets whose checksum holds, and finds every valid packet that
//! garbage (without 0xFF, so no false header can swallow it) surrounds.

use proptest::prelude::*;
use twinloop_link::{Accept, Decoder, PacketWriter, Protocol, checksum_v1, crc16};

const MAX_PACKET: usize = 256;

fn accept_strategy() -> impl Strategy<Value = Accept> {
    prop_oneof![Just(Accept::V1), Just(Accept::V2), Just(Accept::Both)]
}

fn checksum_holds(raw: &[u8], protocol: Protocol) -> bool {
    let n = raw.len();
    match protocol {
        Protocol::V1 => checksum_v1(&raw[2..n - 1]) == raw[n - 1],
        Protocol::V2 => crc16(&raw[..n - 2]) == u16::from_le_bytes([raw[n - 2], raw[n - 1]]),
    }
}

/// Random bytes biased towards header bytes, so headers with wild LENGTH fields
/// appear often.
fn noisy_bytes() -> impl Strategy<Value = Vec<u8>> {
    prop::collection::vec(
        prop_oneof![
            3 => any::<u8>(),
            2 => Just(0xFFu8),
            1 => Just(0xFDu8),
            1 => Just(0x00u8),
        ],
        0..4000,
    )
}

#[derive(Debug, Clone)]
struct Pkt {
    protocol: Protocol,
    id: u8,
    code: u8,
    params: Vec<u8>,
}

fn packet_strategy() -> impl Strategy<Value = Pkt> {
    (
        any::<bool>(),
        0u8..=0xFE,
        any::<u8>(),
        prop::collection::vec(
            prop_oneof![2 => any::<u8>(), 1 => Just(0xFFu8), 1 => Just(0xFDu8)],
            0..60,
        ),
    )
        .prop_map(|(v2, id, code, params)| {
            let protocol = if v2 { Protocol::V2 } else { Protocol::V1 };
            // 2.0 reserves ids 0xFD and 0xFF; 1.0 reserves 0xFF.
            let id = if v2 && id == 0xFD { 0xFC } else { id };
            Pkt {
                protocol,
                id,
                code,
                params,
            }
        })
}

fn encode(p: &Pkt) -> Vec<u8> {
    let mut out = Vec::new();
    let mut w = PacketWriter::raw(&mut out, p.protocol, p.id, p.code);
    w.bytes(&p.params);
    w.finish().unwrap();
    out
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 512, ..ProptestConfig::default() })]

    #[test]
    fn random_streams_never_panic_and_stay_bounded(
        bytes in noisy_bytes(),
        accept in accept_strategy(),
        chunk in 1usize..97,
    ) {
        let mut d = Decoder::with_max_packet(accept, MAX_PACKET);
        let mut rest = &bytes[..];
        while !rest.is_empty() {
            let take = chunk.min(rest.len());
            let n = d.push(&rest[..take]);
            rest = &rest[n..];
            prop_assert!(d.buffered() <= 2 * MAX_PACKET);
            while let Some(f) = d.next_frame() {
                prop_assert!(f.raw.len() <= MAX_PACKET);
                prop_assert!(checksum_holds(f.raw, f.protocol));
            }
        }
        while let Some(f) = d.next_frame_flushing() {
            prop_assert!(checksum_holds(f.raw, f.protocol));
        }
        prop_assert_eq!(d.buffered(), 0);
    }

    #[test]
    fn every_packet_between_garbage_is_recovered(
        items in prop::collection::vec(
            (prop::collection::vec(0u8..0xFF, 0..20), packet_strategy()),
            1..12,
        ),
        chunk in 1usize..64,
    ) {
        let mut stream = Vec::new();
        let mut expected = Vec::new();
        for (garbage, p) in &items {
            stream.extend_from_slice(garbage);
            let bytes = encode(p);
            stream.extend_from_slice(&bytes);
            expected.push((p.clone(), bytes));
        }
        let mut d = Decoder::new(Accept::Both);
        let mut got = Vec::new();
        for c in stream.chunks(chunk) {
            let mut rest = c;
            while !rest.is_empty() {
                let n = d.push(rest);
                rest = &rest[n..];
                while let Some(f) = d.next_frame() {
                    got.push((f.protocol, f.id, f.instruction, f.params.to_vec(), f.raw.to_vec()));
                }
            }
        }
        prop_assert_eq!(got.len(), expected.len());
        for (g, (p, bytes)) in got.iter().zip(&expected) {
            prop_assert_eq!(g.0, p.protocol);
            prop_assert_eq!(g.1, p.id);
            prop_assert_eq!(g.2, p.code);
            prop_assert_eq!(&g.3, &p.params);
            prop_assert_eq!(&g.4, bytes);
        }
    }
}
