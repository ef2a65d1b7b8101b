//! Packets against the e-manual's printed examples (independent truth), CRC-16
//! against the SDK's table, byte stuffing, and the streaming decoder's resync.

use twinloop_link::crc16::{CRC16_TABLE, crc16};
use twinloop_link::packet::{stuff_in_place, unstuff_into};
use twinloop_link::{Accept, Decoder, PacketWriter, Protocol};

struct Example {
    line: usize,
    protocol: Protocol,
    status: bool,
    id: u8,
    code: u8,
    params: Vec<u8>,
    wire: Vec<u8>,
}

fn hex_bytes(text: &str, line: usize) -> Vec<u8> {
    text.split_whitespace()
        .map(|t| u8::from_str_radix(t, 16).unwrap_or_else(|_| panic!("line {line}: bad hex {t:?}")))
        .collect()
}

fn examples() -> Vec<Example> {
    let text = include_str!("data/emanual_packets.txt");
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        let line_no = k + 1;
        let line = line.split('#').next().unwrap().trim();
        if line.is_empty() {
            continue;
        }
        let (fields, wire) = line
            .split_once('|')
            .expect("a | separates fields and wire bytes");
        let mut f = fields.split_whitespace();
        let protocol = Protocol::parse(f.next().unwrap()).unwrap();
        let status = match f.next().unwrap() {
            "I" => false,
            "S" => true,
            other => panic!("line {line_no}: kind {other}"),
        };
        let rest: Vec<&str> = f.collect();
        let nums = hex_bytes(&rest.join(" "), line_no);
        out.push(Example {
            line: line_no,
            protocol,
            status,
            id: nums[0],
            code: nums[1],
            params: nums[2..].to_vec(),
            wire: hex_bytes(wire, line_no),
        });
    }
    assert!(out.len() >= 30, "fixture lost examples: {}", out.len());
    out
}

fn encode(e: &Example) -> Vec<u8> {
    let mut out = Vec::new();
    let mut w = if e.status {
        PacketWriter::status(&mut out, e.protocol, e.id, e.code)
    } else {
        PacketWriter::raw(&mut out, e.protocol, e.id, e.code)
    };
    w.bytes(&e.params);
    w.finish().unwrap();
    out
}

#[test]
fn encoder_matches_every_emanual_example() {
    for e in examples() {
        assert_eq!(
            encode(&e),
            e.wire,
            "emanual_packets.txt line {}: encoded bytes differ",
            e.line
        );
    }
}

#[test]
fn decoder_reads_every_emanual_example() {
    for e in examples() {
        let mut d = Decoder::new(Accept::Both);
        assert_eq!(d.push(&e.wire), e.wire.len());
        let f = d
            .next_frame()
            .unwrap_or_else(|| panic!("line {}: no frame", e.line));
        assert_eq!(f.protocol, e.protocol, "line {}", e.line);
        assert_eq!(f.id, e.id, "line {}", e.line);
        assert_eq!(f.raw, &e.wire[..], "line {}", e.line);
        match (e.protocol, e.status) {
            (Protocol::V2, true) => {
                assert_eq!(f.instruction, 0x55, "line {}", e.line);
                assert_eq!(f.params[0], e.code, "line {}", e.line);
                assert_eq!(&f.params[1..], &e.params[..], "line {}", e.line);
            }
            _ => {
                assert_eq!(f.instruction, e.code, "line {}", e.line);
                assert_eq!(f.params, &e.params[..], "line {}", e.line);
            }
        }
        assert!(d.next_frame().is_none());
    }
}

#[test]
fn crc_table_matches_the_sdk_table_and_check_vectors() {
    // First and last rows of the table printed in the SDK's updateCRC.
    assert_eq!(
        &CRC16_TABLE[..8],
        &[
            0x0000, 0x8005, 0x800F, 0x000A, 0x801B, 0x001E, 0x0014, 0x8011
        ]
    );
    assert_eq!(&CRC16_TABLE[253..], &[0x820D, 0x8207, 0x0202]);
    // EM-P2 check vectors (e-manual Protocol 2.0, CRC).
    assert_eq!(
        crc16(&[0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x03, 0x00, 0x01]),
        0x4E19
    );
    assert_eq!(
        crc16(&[
            0xFF, 0xFF, 0xFD, 0x00, 0xFE, 0x09, 0x00, 0x82, 0x84, 0x00, 0x04, 0x00, 0x01, 0x02
        ]),
        0xFACE
    );
}

#[test]
fn stuffing_of_minus_131073_both_ways() {
    // A present position of -131073 is FF FF FD FF little-endian; on the wire the
    // pattern FF FF FD gets an extra FD (e-manual Protocol 2.0, packet process).
    let value: i32 = -131073;
    assert_eq!(value.to_le_bytes(), [0xFF, 0xFF, 0xFD, 0xFF]);
    let mut out = Vec::new();
    let mut w = PacketWriter::status(&mut out, Protocol::V2, 1, 0);
    w.bytes(&value.to_le_bytes());
    w.finish().unwrap();
    // LENGTH = 55 + ERR + 5 stuffed data bytes + CRC = 9.
    assert_eq!(
        &out[..12],
        &[
            0xFF, 0xFF, 0xFD, 0x00, 0x01, 0x09, 0x00, 0x55, 0x00, 0xFF, 0xFF, 0xFD
        ]
    );
    assert_eq!(out[12], 0xFD, "stuffed byte");
    assert_eq!(out[13], 0xFF);
    let crc = crc16(&out[..14]);
    assert_eq!(&out[14..], &crc.to_le_bytes());

    let mut d = Decoder::new(Accept::V2);
    d.push(&out);
    let f = d.next_frame().unwrap();
    assert_eq!(f.params, &[0x00, 0xFF, 0xFF, 0xFD, 0xFF]);
    assert_eq!(
        i32::from_le_bytes(f.params[1..5].try_into().unwrap()),
        value
    );
}

#[test]
fn stuffing_round_trips_awkward_patterns() {
    let cases: &[&[u8]] = &[
        &[0xFF, 0xFF, 0xFD],
        &[0xFF, 0xFF, 0xFD, 0xFD],
        &[0xFF, 0xFF, 0xFF, 0xFD, 0xFF, 0xFF, 0xFD, 0xFD, 0x00],
        &[0xFD, 0xFF, 0xFF, 0xFD, 0xFF],
        &[0xFF, 0xFF, 0xFD, 0xFF, 0xFF, 0xFD, 0xFF, 0xFF, 0xFD],
    ];
    for c in cases {
        let mut buf = vec![0xAA];
        buf.extend_from_slice(c);
        stuff_in_place(&mut buf, 1);
        let mut back = Vec::new();
        unstuff_into(&buf[1..], &mut back);
        assert_eq!(&back[..], *c, "stuffed {:02X?}", &buf[1..]);
    }
    // The e-manual's rule exactly: FF FF FD -> FF FF FD FD.
    let mut b = vec![0xFF, 0xFF, 0xFD, 0x01];
    stuff_in_place(&mut b, 0);
    assert_eq!(b, [0xFF, 0xFF, 0xFD, 0xFD, 0x01]);
}

fn packet(protocol: Protocol, id: u8, code: u8, params: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    let mut w = PacketWriter::raw(&mut out, protocol, id, code);
    w.bytes(params);
    w.finish().unwrap();
    out
}

#[test]
fn decoder_resyncs_after_garbage_truncation_and_bad_checksum() {
    let good1 = packet(Protocol::V2, 3, 0x02, &[0x84, 0x00, 0x04, 0x00]);
    let good2 = packet(Protocol::V1, 7, 0x02, &[0x24, 0x02]);
    let mut bad = packet(Protocol::V2, 4, 0x03, &[0x74, 0x00, 1, 2, 3, 4]);
    let n = bad.len();
    bad[n - 1] ^= 0x01; // CRC broken
    let truncated = &good1[..9];

    let mut stream = vec![0x00, 0x13, 0xFF, 0x42, 0xFF, 0xFF, 0xFF];
    stream.extend_from_slice(truncated);
    stream.extend_from_slice(&good2);
    stream.extend_from_slice(&bad);
    stream.extend_from_slice(&good1);
    stream.extend_from_slice(&[0xFF, 0xFF, 0x01]);

    // Byte by byte, the hardest way for a streaming decoder.
    let mut d = Decoder::new(Accept::Both);
    let mut got: Vec<Vec<u8>> = Vec::new();
    for b in &stream {
        assert_eq!(d.push(std::slice::from_ref(b)), 1);
        while let Some(f) = d.next_frame() {
            got.push(f.raw.to_vec());
        }
    }
    assert_eq!(got, vec![good2.clone(), good1.clone()]);
    assert!(d.stats().bad_checksums >= 2, "{:?}", d.stats());
    // The trailing partial header is given up when the line goes quiet.
    assert!(d.next_frame_flushing().is_none());
    assert_eq!(d.buffered(), 0);
}

#[test]
fn decoder_refuses_huge_length_without_allocating() {
    // A 2.0 header claiming 65535 bytes: rejected as oversized, then the real packet.
    let good = packet(Protocol::V2, 1, 0x01, &[]);
    let mut stream = vec![0xFF, 0xFF, 0xFD, 0x00, 0x01, 0xFF, 0xFF, 0x01];
    stream.extend_from_slice(&good);
    let mut d = Decoder::with_max_packet(Accept::V2, 64);
    d.push(&stream);
    assert_eq!(d.next_frame().unwrap().raw, &good[..]);
    assert_eq!(d.stats().oversized, 1);
}

#[test]
fn one_point_zero_id_253_and_two_point_zero_share_a_line() {
    let v1 = packet(Protocol::V1, 0xFD, 0x01, &[]);
    let v2 = packet(Protocol::V2, 0x01, 0x01, &[]);
    let mut d = Decoder::new(Accept::Both);
    d.push(&v1);
    d.push(&v2);
    let f = d.next_frame().unwrap();
    assert_eq!((f.protocol, f.id), (Protocol::V1, 0xFD));
    let f = d.next_frame().unwrap();
    assert_eq!((f.protocol, f.id), (Protocol::V2, 0x01));
    // A 1.0-only decoder does not mistake a 2.0 packet for one of its own.
    let mut d1 = Decoder::new(Accept::V1);
    d1.push(&v2);
    assert!(d1.next_frame_flushing().is_none());
}

#[test]
fn encoder_refuses_what_the_protocol_cannot_carry() {
    use twinloop_link::{EncodeError, Instruction};
    let mut out = Vec::new();
    let mut w = PacketWriter::instruction(&mut out, Protocol::V1, 1, Instruction::Read);
    w.address(300).u8(2);
    assert_eq!(
        w.finish(),
        Err(EncodeError::AddressTooLarge { address: 300 })
    );
    assert!(out.is_empty());
    let w = PacketWriter::instruction(&mut out, Protocol::V1, 1, Instruction::SyncRead);
    assert!(matches!(w.finish(), Err(EncodeError::NotInProtocol { .. })));
    let mut w = PacketWriter::instruction(&mut out, Protocol::V1, 1, Instruction::Write);
    w.address(30).bytes(&[0u8; 300]);
    assert!(matches!(w.finish(), Err(EncodeError::TooLong { .. })));
}
