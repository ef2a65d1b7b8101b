//! twinloop-ident's tests, in one binary (one link step instead of six).

mod butterworth;
mod identifiability;
mod markers;
mod oracle;
mod poses_format;
mod recovery;
mod squat;
mod units;
