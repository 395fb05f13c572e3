//! The trace of a run found by the exploration: from the initial state along the stored
//! parent links to a state, its steps found again by the step relation.

use bip_model::{OwnedStep, State, Steps, System, Trace};

use crate::error::VerifyError;
use crate::visited::{StateId, Visited};

/// The trace from the initial state to stored state `id`, then `last` if given (a step
/// of that state). The steps are found again by firing the enabled steps of each state
/// on the path until one leads to the next state.
pub(super) fn trace_to(
    system: &System,
    visited: &Visited,
    id: StateId,
    last: Option<OwnedStep>,
    verdict: bip_model::Verdict,
) -> Result<Trace, VerifyError> {
    let layout = &system.layout;
    let path = visited.path_to(id);
    let mut steps = Steps::new();
    let mut next = system.initial_state();
    let mut packed = vec![0u8; layout.bytes()];
    let mut out: Vec<(OwnedStep, State)> = Vec::with_capacity(path.len());
    let mut state = layout.unpack(visited.state(path[0]));
    for &to in &path[1..] {
        let target = visited.state(to);
        system.enabled_steps(&state, &mut steps).map_err(|e| {
            VerifyError::Internal(format!("a state on a trace has a range error: {e}"))
        })?;
        let mut taken = None;
        for step in steps.iter() {
            if system.fire(&state, step, &mut next).is_ok() {
                layout.encode(&next, &mut packed);
                if packed == target {
                    taken = Some(step.to_owned());
                    break;
                }
            }
        }
        let step = taken.ok_or_else(|| {
            VerifyError::Internal("no step leads to the next state of a trace".into())
        })?;
        state = next.clone();
        out.push((step, next.clone()));
    }
    if let Some(step) = last {
        system
            .fire(&state, step.as_step(), &mut next)
            .map_err(|e| VerifyError::Internal(format!("the last step of a trace fails: {e}")))?;
        out.push((step, next));
    }
    Ok(Trace::from_path(system, verdict, &out))
}
