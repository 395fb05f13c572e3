//! What an [`crate::EnabledSet`] keeps of an interaction's last evaluation, and what a
//! fire plan's effects fix ahead of time ([`crate::PlanEffects`]).

use crate::step_tables::Entry;

/// What the last evaluation of an interaction found: `width` picks per step (0: no step),
/// in `pool[start..start + len]` if `in_pool`; `ready` if its required ports all had an
/// enabled transition (only then does what the connector's guard reads matter).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Found {
    pub(crate) start: u32,
    pub(crate) len: u32,
    pub(crate) width: u32,
    pub(crate) ready: bool,
    pub(crate) in_pool: bool,
}

impl Found {
    /// A step table entry's steps.
    #[inline(always)]
    pub(crate) fn of(e: &Entry) -> Found {
        let (start, len) = e.span();
        Found {
            start,
            len,
            width: e.width() as u32,
            ready: e.ready(),
            in_pool: true,
        }
    }
}
