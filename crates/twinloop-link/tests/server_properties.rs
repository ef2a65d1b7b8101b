//! The virtual bus never panics on what a host may send: random bytes, and
//! checksum-valid packets of every instruction code with random parameters, to
//! servos of both protocols.

use proptest::prelude::*;
use twinloop_link::transport::Responder;
use twinloop_link::{BusServo, PacketWriter, Protocol, ServoModel, VirtualBus};

fn servos() -> Vec<BusServo> {
    vec![
        BusServo {
            id: 1,
            model: ServoModel::Xm430W350,
        },
        BusServo {
            id: 2,
            model: ServoModel::Xl430W250,
        },
        BusServo {
            id: 3,
            model: ServoModel::Mx64V2,
        },
        BusServo {
            id: 1,
            model: ServoModel::Rx28,
        },
        BusServo {
            id: 2,
            model: ServoModel::Mx106,
        },
    ]
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 1000, ..ProptestConfig::default() })]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..2000)) {
        let mut bus = VirtualBus::with_tracking_model(&servos());
        let mut reply = Vec::new();
        for chunk in bytes.chunks(37) {
            bus.respond(chunk, &mut reply);
        }
    }

    #[test]
    fn valid_packets_with_random_parameters_never_panic(
        packets in prop::collection::vec(
            (
                any::<bool>(),
                prop_oneof![Just(1u8), Just(2u8), Just(0xFEu8), any::<u8>()],
                prop_oneof![
                    Just(0x01u8), Just(0x02), Just(0x03), Just(0x04), Just(0x05), Just(0x06),
                    Just(0x08), Just(0x10), Just(0x82), Just(0x83), Just(0x8A), Just(0x92),
                    Just(0x93), Just(0x9A), any::<u8>()
                ],
                prop::collection::vec(any::<u8>(), 0..40),
            ),
            1..20,
        ),
        step in 0.0f64..0.1,
    ) {
        let mut bus = VirtualBus::with_tracking_model(&servos());
        let mut reply = Vec::new();
        for (v2, id, code, params) in packets {
            let protocol = if v2 { Protocol::V2 } else { Protocol::V1 };
            let id = if id == 0xFF || (v2 && id == 0xFD) { 0xFE } else { id };
            let mut p = Vec::new();
            let mut w = PacketWriter::raw(&mut p, protocol, id, code);
            w.bytes(&params);
            w.finish().unwrap();
            bus.respond(&p, &mut reply);
            bus.step(step);
        }
    }
}
