//! A component's async codels in the generated glue (docs/codegen.md, "Running C codels
//! on the engine"): each is bound apart from the module object (bip-engine's
//! `EngineBuilder::apart`), so that it runs on its own thread while the object serves
//! the component's other codels. It runs on a copy of the object's memory taken when it
//! begins, with a context of its own, and what it may write (its service's parameters and
//! locals, its `out` and `inout` ids members, the ports it writes) goes back into the
//! object's memory when it returns. The object is shared behind a lock, taken for each of
//! its codels' calls and, by the async codel, only for the copy and the write-back.

use std::fmt::Write as _;

use super::codels::Place;
use super::glue_args::{place_in, service_field};
use crate::CodegenError;

/// What an async codel writes back: the places of the state it may have changed.
pub struct Apart {
    /// Its number among the module object's codels.
    pub k: usize,
    /// The ids members and ports it writes.
    places: Vec<Place>,
    /// Its service, whose storage it owns while it runs (`None`: a task's codel).
    service: Option<String>,
}

impl Apart {
    pub fn new(k: usize, service: Option<&str>) -> Apart {
        Apart {
            k,
            places: Vec::new(),
            service: service.map(str::to_string),
        }
    }

    /// Notes a parameter at `place` that the codel writes.
    pub fn writes(&mut self, place: &Place) {
        // the service's storage goes back whole
        if !matches!(place, Place::Service(_)) {
            self.places.push(place.clone());
        }
    }

    /// The assignments back, from `a` to `s`, each place once, none inside another.
    fn swaps(&self, has_storage: bool) -> Result<Vec<String>, CodegenError> {
        let mut exprs: Vec<(String, String)> = Vec::new();
        if let (Some(s), true) = (&self.service, has_storage) {
            let f = service_field(s);
            exprs.push((format!("(*s).{f}"), format!("(*a).{f}")));
        }
        for p in &self.places {
            let service = self.service.as_deref();
            exprs.push((place_in("s", p, service)?, place_in("a", p, service)?));
        }
        exprs.sort();
        exprs.dedup();
        let outer: Vec<String> = exprs.iter().map(|(s, _)| s.clone()).collect();
        let inside = |e: &str| {
            outer.iter().any(|o| {
                e.len() > o.len()
                    && e.starts_with(o.as_str())
                    && matches!(e.as_bytes()[o.len()], b'.' | b'[')
            })
        };
        Ok(exprs
            .into_iter()
            .filter(|(s, _)| !inside(s))
            .map(|(s, a)| format!("core::mem::swap(&mut {s}, &mut {a});"))
            .collect())
    }
}

/// `write_back` (what each async codel's run gives back to the object's memory) and the
/// runner of an async codel, for a component whose async codels are `apart`; `storages`
/// names the services that have storage.
pub fn apart_glue(
    out: &mut String,
    apart: &[Apart],
    storages: &[String],
) -> Result<(), CodegenError> {
    out.push_str("/// Gives the object's memory `s` what async codel `k`'s run on the copy `a` may have\n/// written (its service's storage, its `out` and `inout` ids members, the ports it\n/// writes), leaving the rest of `a` to be dropped.\n///\n/// # Safety\n/// `s` and `a` are valid and distinct.\n// (a match for every component, whatever the number of its async codels)\n#[allow(unused_variables, clippy::single_match)]\nunsafe fn write_back(k: usize, s: *mut State, a: *mut State) {\n    unsafe {\n        match k {\n");
    for a in apart {
        let has_storage = a.service.as_ref().is_some_and(|s| storages.contains(s));
        let _ = writeln!(
            out,
            "            {} => {{ {} }}",
            a.k,
            a.swaps(has_storage)?.join(" ")
        );
    }
    out.push_str("            _ => {}\n        }\n    }\n}\n\n");
    out.push_str(
        r#"/// An async codel of the component, run apart from its module object: on a copy of the
/// object's memory taken when the codel begins, with a context of its own, its writes
/// given back when it returns.
struct Apart {
    k: usize,
    module: std::sync::Arc<std::sync::Mutex<Component>>,
    context: bip_genom_c::Context,
    events: bip_genom_c::Events,
}

impl Apart {
    fn new(k: usize, module: &std::sync::Arc<std::sync::Mutex<Component>>) -> Apart {
        let context = match module.lock() {
            Ok(m) => m.context.beside(),
            Err(_) => bip_genom_c::Context::default(),
        };
        Apart { k, module: std::sync::Arc::clone(module), context, events: events() }
    }

    // (the state is `Copy` for some components, not for others: written alike for all)
    #[allow(clippy::clone_on_copy)]
    fn run(&mut self, ctx: &mut bip_genom_c::bip_engine::Ctx<'_>) -> bip_genom_c::bip_engine::Next {
        let Ok(mut copy) = self.module.lock().map(|m| m.state.clone()) else {
            return bip_genom_c::bip_engine::Next::Declared(u16::MAX);
        };
        let next = run_on(self.k, &mut copy, &self.context, &self.events, ctx);
        if let Ok(mut m) = self.module.lock() {
            // SAFETY: two distinct states, both alive
            unsafe { write_back(self.k, &mut m.state, &mut copy) };
        }
        next
    }
}

"#,
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_place_goes_back_once_and_none_inside_another() {
        let mut a = Apart::new(3, Some("GoTo"));
        a.writes(&Place::Ids(vec!["frames".into()]));
        a.writes(&Place::Service(vec!["route".into()]));
        a.writes(&Place::Port("image".into()));
        a.writes(&Place::Ids(vec!["frames".into()]));
        a.writes(&Place::Ids(vec!["framesets".into()]));
        let swaps = a.swaps(true).expect("places");
        assert_eq!(
            swaps,
            [
                "core::mem::swap(&mut (*s).ids.frames, &mut (*a).ids.frames);",
                "core::mem::swap(&mut (*s).ids.framesets, &mut (*a).ids.framesets);",
                "core::mem::swap(&mut (*s).port_image, &mut (*a).port_image);",
                "core::mem::swap(&mut (*s).svc_GoTo, &mut (*a).svc_GoTo);",
            ]
        );
        // the whole ids take in their members
        a.writes(&Place::Ids(Vec::new()));
        let swaps = a.swaps(false).expect("places");
        assert_eq!(
            swaps,
            [
                "core::mem::swap(&mut (*s).ids, &mut (*a).ids);",
                "core::mem::swap(&mut (*s).port_image, &mut (*a).port_image);",
            ]
        );
    }
}
