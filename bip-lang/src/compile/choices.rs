//! The limit on an interaction's steps in one state (bip-model's `choices`): a connector
//! that could go past it is refused here, where its place in the file is known.

use crate::diag::ModelError;
use crate::syntax::SystemDef;
use bip_model::choices::{most_enabled, most_steps, MAX_CHOICES};
use bip_model::{Atom, Component, Connector, Interaction};

/// An error for each connector of `def` one of whose instances may have more than
/// [`MAX_CHOICES`] steps in one state.
pub(super) fn check(
    def: &SystemDef,
    atoms: &[Atom],
    components: &[Component],
    connectors: &[Connector],
    interactions: &[Interaction],
) -> Vec<ModelError> {
    let most: Vec<Vec<u32>> = atoms.iter().map(most_enabled).collect();
    let mut errors = Vec::new();
    for c in connectors {
        let worst = c
            .interactions
            .clone()
            .map(|i| {
                let inter = &interactions[i as usize];
                (most_steps(components, &most, inter), inter)
            })
            .max_by_key(|(n, _)| *n);
        let Some((steps, inter)) = worst.filter(|(n, _)| *n > MAX_CHOICES) else {
            continue;
        };
        let Some(cd) = def.connectors.iter().find(|cd| cd.name.as_str() == c.name) else {
            continue;
        };
        // the ports with a choice, and the largest one
        let factors: Vec<u32> = inter
            .ports
            .iter()
            .map(|p| most[components[p.component as usize].atom as usize][p.port as usize])
            .filter(|&f| f > 1)
            .collect();
        let largest = factors.iter().copied().max().unwrap_or(0);
        let count = if steps == u64::MAX {
            "more than 18446744073709551615".to_string()
        } else {
            steps.to_string()
        };
        errors.push(
            ModelError::new(
                format!(
                    "connector `{}` may have {count} steps in one state, more than \
                     {MAX_CHOICES}",
                    c.name
                ),
                cd.name.span,
            )
            .with_label("this connector")
            .with_help(format!(
                "each combination of one enabled transition per participant is a step: \
                 {} of its ports have transitions that can be enabled together (up to \
                 {largest} on one); split the connector, or give a port's transitions \
                 guards that cannot hold together",
                factors.len()
            )),
        );
    }
    errors
}
