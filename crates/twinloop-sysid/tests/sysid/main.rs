//! twinloop-sysid against independent oracles (numpy, python-control, slycot, scipy:
//! tools/oracle/sysid_reference.py, fixtures in tests/data) and on bad input. One
//! test binary, so the release build links once.

mod arx_oracle;
mod bad_input;
mod common;
mod gramian_oracle;
mod identification;
