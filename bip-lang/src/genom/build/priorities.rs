//! The generated priorities (codels urgent, requests when the layer is quiescent,
//! activities in declaration order), followed by the user's.

use super::{Builder, UserTexts};
use crate::genom::names::TICK;
use crate::genom::tree::name;
use crate::syntax::{ExprDef, PriorityDef};

impl<'a, 'd> Builder<'a, 'd> {
    /// Codels are urgent (the tick is below every codel step), requests and the returns
    /// of async codels wait for the functional layer to be quiescent (below every codel
    /// step), and codels of different
    /// activities run in declaration order (earlier activities above later ones); the
    /// modules' wake-ups are above all of them. The
    /// declared priorities form a chain through the last activity; the core closes them
    /// transitively. Then the user's priorities.
    pub(super) fn priorities(&mut self, user: &UserTexts) -> Vec<PriorityDef> {
        let mut out = match self.timed {
            Some(t) => self.timed_priorities(t),
            None => self.untimed_priorities(),
        };
        for (k, p) in self.def.priorities.iter().enumerate() {
            let mut p = p.clone();
            if let (Some(u), Some(written)) = (user.priority_whens.get(&k), &p.when) {
                p.when = Some(u.def(written));
            }
            out.push(p);
        }
        out
    }

    fn untimed_priorities(&self) -> Vec<PriorityDef> {
        let mut levels: Vec<Vec<String>> = Vec::new(); // codel connectors per activity
        let mut requests: Vec<String> = Vec::new();
        for m in &self.recipe.modules {
            for s in &m.services {
                requests.extend(s.request.clone());
                // a request's other outcomes: its function's codel fails, or its
                // `validate` codel refuses it
                requests.extend(s.function.iter().chain(&s.validate).map(|c| c.fail.clone()));
                if s.component.is_some() {
                    // a pending request's interrupts are urgent too: they come before the
                    // tick that could start what they interrupt
                    let mut level: Vec<String> = s.interrupt.iter().cloned().collect();
                    for c in &s.codels {
                        level.push(c.run.clone());
                        level.push(c.fail.clone());
                        // an async codel starts as a codel runs, and returns when the
                        // world lets it, as a request comes
                        if let Some((start, ret)) = &c.apart {
                            level.push(start.clone());
                            requests.push(ret.clone());
                        }
                    }
                    levels.push(level);
                }
            }
        }
        let pr = |low: &str, high: &str| PriorityDef {
            low: ExprDef::Built(name(low)),
            high: ExprDef::Built(name(high)),
            when: None,
        };
        let mut out = Vec::new();
        if let Some(last) = levels.last() {
            for high in last {
                out.push(pr(TICK, high));
                for r in &requests {
                    out.push(pr(r, high));
                }
            }
        }
        // a module's wake-up is delivered before anything else happens
        if let Some(first) = levels.first() {
            for wake in &self.wakes {
                for low in first {
                    out.push(pr(low, wake));
                }
            }
        }
        for pair in levels.windows(2) {
            for low in &pair[1] {
                for high in &pair[0] {
                    out.push(pr(low, high));
                }
            }
        }
        out
    }
}
