//! Task machines (docs/genom.md, "Task machines"): a task's own codels become an activity
//! of its module, marked `machine`, named like the task and run in that task, placed
//! before the module's services so that its codels run before theirs within an instant.
//! Everything downstream (checks, expansion, names in expressions, the engine's map)
//! then treats it as an activity, except where it differs: it starts with the component,
//! and nothing requests, interrupts or aborts it.

use std::borrow::Cow;

use crate::syntax::{ServiceDef, ServiceKind, SystemDef};

/// `def` with each task's machine as an activity of its module; borrowed if no task has
/// codels.
pub(super) fn as_activities(def: &SystemDef) -> Cow<'_, SystemDef> {
    if !def
        .modules
        .iter()
        .any(|m| m.tasks.iter().any(|t| t.has_machine()))
    {
        return Cow::Borrowed(def);
    }
    let mut out = def.clone();
    for m in &mut out.modules {
        let machines: Vec<ServiceDef> = m
            .tasks
            .iter()
            .filter(|t| t.has_machine())
            .map(|t| ServiceDef {
                name: t.name.clone(),
                kind: ServiceKind::Activity,
                doc: None,
                task: Some(t.name.clone()),
                interrupts: Vec::new(),
                after: Vec::new(),
                before: Vec::new(),
                codels: t.codels.clone(),
                validate: None,
                args: None,
                output: None,
                machine: true,
            })
            .collect();
        m.services.splice(0..0, machines);
    }
    Cow::Owned(out)
}
