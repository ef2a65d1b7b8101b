//! The loop's adaptation of a model to a tip-over measured over a bus: on the link
//! the CoM inversion gives, less the protocol's bias (`protocol_bias`), then, where
//! asked, on the links below the ankles (`other_places`). Its own file so that
//! neither of the two imports the other.

use crate::LoopError;
use crate::floor_share::add_floor_share;
use crate::other_places::try_other_places;
use crate::protocol_bias::{Calibration, Replay, adapt_on_one_place};
use twinloop_description::Description;
use twinloop_ident::IdentError;
use twinloop_ident::adapt::{AdaptOptions, Adapted};
use twinloop_ident::tipover_study::StudyReport;

/// Adapt `prior` to `study` in `replay.passes` passes (see [`crate::protocol_bias`]); with no passes, no model placed, or a tip-over not measured over
/// a bus, the plain adaptation. With `replay.other_places`, the part is also tried on
/// the links below the ankles ([`crate::other_places`]). The CoM's resolution then
/// takes the fitted floor's share ([`crate::floor_share`]). `map_err` words the
/// adaptation's errors for the caller's flags.
pub fn adapt_to_protocol(
    prior: &Description,
    study: &StudyReport,
    opts: &AdaptOptions,
    replay: &Replay<'_>,
    log: &mut dyn FnMut(&str),
    map_err: &(dyn Fn(IdentError) -> LoopError + Sync),
) -> Result<(Adapted, Option<Calibration>), LoopError> {
    let first = adapt_on_one_place(prior, study, opts, replay, log, map_err)?;
    let mut kept = if !replay.other_places || opts.host.is_some() || opts.total_mass.is_none() {
        first
    } else {
        try_other_places(prior, study, opts, replay, first, log, map_err)?
    };
    if let Err(e) = add_floor_share(prior, study, opts, replay, &mut kept, log) {
        // The model found stands; only its bound is short of the floor's share.
        let line = format!(
            "the floor's share of the CoM's resolution could not be measured ({e}): the \
             resolution given is the angles' alone"
        );
        log(&line);
        kept.0.report.notes.push(line);
    }
    Ok(kept)
}
