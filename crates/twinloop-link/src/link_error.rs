//! What can go wrong in one exchange with one servo. Every variant names the servo;
//! none allocates except [`LinkError::Io`] (the link itself is gone), so error
//! paths in a control loop stay allocation-free too.

use crate::packet::EncodeError;
use crate::status_error::StatusError;
use std::fmt;
use std::io;
use std::sync::Arc;

#[derive(Debug, Clone)]
pub enum LinkError {
    /// The transport failed: adapter unplugged, peer closed, permission lost.
    Io(Arc<io::Error>),
    /// No status packet arrived in time.
    Timeout { id: u8 },
    /// Bytes arrived but none formed a valid status packet from this servo (bad
    /// checksum or CRC, truncated packet).
    Corrupt { id: u8 },
    /// A valid packet from this servo, but not the reply expected (wrong length or
    /// order): discarded.
    WrongReply {
        id: u8,
        expected_len: usize,
        got_len: usize,
    },
    /// The reply passed its checksum but holds a value no healthy servo reports
    /// (outside the register's range): discarded as corrupt.
    Implausible { id: u8, register: &'static str },
    /// Verified reads (Protocol 1.0): no two consecutive replies agreed byte for
    /// byte, so none is trusted.
    Unverified { id: u8 },
    /// The servo answered with an error that means it did not execute the
    /// instruction.
    /// `register`: the address and length the request named, when it named one.
    Rejected {
        id: u8,
        error: StatusError,
        register: Option<(u16, u16)>,
    },
    /// The request could not be encoded (e.g. an instruction the protocol lacks).
    Encode(EncodeError),
}

impl LinkError {
    /// Whether trying again may help (lost or damaged bytes), as opposed to a refusal
    /// or a dead link.
    pub fn is_transient(&self) -> bool {
        match self {
            LinkError::Timeout { .. }
            | LinkError::Corrupt { .. }
            | LinkError::WrongReply { .. }
            | LinkError::Implausible { .. }
            | LinkError::Unverified { .. } => true,
            // The servo saw our request damaged (checksum / CRC error): send it again.
            LinkError::Rejected { error, .. } => error.instruction_damaged(),
            LinkError::Io(_) | LinkError::Encode(_) => false,
        }
    }

    /// The servo id the error concerns, if one.
    pub fn id(&self) -> Option<u8> {
        match self {
            LinkError::Timeout { id }
            | LinkError::Corrupt { id }
            | LinkError::WrongReply { id, .. }
            | LinkError::Implausible { id, .. }
            | LinkError::Unverified { id }
            | LinkError::Rejected { id, .. } => Some(*id),
            LinkError::Io(_) | LinkError::Encode(_) => None,
        }
    }

    /// A short machine-friendly name ("timeout", "corrupt", ...).
    pub fn kind(&self) -> &'static str {
        match self {
            LinkError::Io(_) => "io",
            LinkError::Timeout { .. } => "timeout",
            LinkError::Corrupt { .. } => "corrupt",
            LinkError::WrongReply { .. } => "wrong-reply",
            LinkError::Implausible { .. } => "implausible",
            LinkError::Unverified { .. } => "unverified",
            LinkError::Rejected { .. } => "rejected",
            LinkError::Encode(_) => "encode",
        }
    }
}

impl fmt::Display for LinkError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LinkError::Io(e) => write!(f, "link failed: {e}"),
            LinkError::Timeout { id } => write!(f, "servo id {id}: no reply (timeout)"),
            LinkError::Corrupt { id } => {
                write!(f, "servo id {id}: reply corrupted (checksum or truncation)")
            }
            LinkError::WrongReply {
                id,
                expected_len,
                got_len,
            } => write!(
                f,
                "servo id {id}: reply with {got_len} data bytes, expected {expected_len}"
            ),
            LinkError::Implausible { id, register } => {
                write!(f, "servo id {id}: implausible {register} value, discarded")
            }
            LinkError::Unverified { id } => write!(
                f,
                "servo id {id}: repeated reads disagreed (verified read), discarded"
            ),
            LinkError::Rejected {
                id,
                error,
                register: Some((address, len)),
            } => write!(
                f,
                "servo id {id}, register at address {address} ({len} bytes): {error}"
            ),
            LinkError::Rejected { id, error, .. } => write!(f, "servo id {id}: {error}"),
            LinkError::Encode(e) => write!(f, "cannot encode request: {e}"),
        }
    }
}

impl std::error::Error for LinkError {}

impl From<io::Error> for LinkError {
    fn from(e: io::Error) -> LinkError {
        LinkError::Io(Arc::new(e))
    }
}

impl From<EncodeError> for LinkError {
    fn from(e: EncodeError) -> LinkError {
        LinkError::Encode(e)
    }
}

/// The outcome of one servo's part of an exchange: `Ok` carries the status error
/// byte when the servo executed the instruction but reported a condition (overload,
/// Alert), `Err` means no valid data.
pub type Outcome = Result<StatusError, LinkError>;
