//! The servo catalogue's loop registers (twinloop-servos) against the control tables:
//! the same address, size, initial value and maximum for every servo.

use twinloop_link::{Item, ModelTable, ServoModel};

#[test]
fn the_catalogues_loop_registers_are_the_control_tables() {
    for m in ServoModel::SERVOS {
        let table = m.table();
        for r in m.loop_registers() {
            let reg = table
                .registers
                .iter()
                .find(|t| t.address == r.address)
                .unwrap_or_else(|| panic!("{m}: no register at {}", r.address));
            assert_eq!(reg.name, r.name, "{m}");
            assert_eq!(reg.size, r.size, "{m} {}", r.name);
            assert_eq!(reg.initial, Some(r.factory), "{m} {}", r.name);
            assert_eq!(reg.max, r.max, "{m} {}", r.name);
        }
        // The P gain's factory value is the catalogue's.
        if let (Some(p), Some(g)) = (table.item(Item::PositionPGain), m.factory_gains()) {
            assert_eq!(p.initial, Some(g[0]), "{m}");
        }
    }
}
