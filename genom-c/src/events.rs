//! The `genom_event` a codel returns, read as the engine's [`Next`]. An event is a pointer
//! to its name, defined once by the linker (the headers define them weak), so it is
//! recognised by its address alone: nothing here reads through a pointer a codel returns,
//! which may be garbage.

use bip_engine::{CodelSignature, Next};

use crate::context::GenomEvent;

/// A component's events and exceptions by address, and each codel's declared outcomes.
pub struct Events {
    /// Per codel of the module object, the addresses of its declared yields, then of its
    /// declared exceptions: what `Next::Declared` numbers.
    declared: Vec<Box<[usize]>>,
    /// Every yield and exception of the component, with its name in the model.
    yields: Vec<(usize, &'static str)>,
    exceptions: Vec<(usize, &'static str)>,
}

impl Events {
    /// The events of a component: its yields' and exceptions' addresses with their names
    /// in the model (`pause::step`, `e_limit`), and the codels of its module object.
    pub fn new(
        codels: &[CodelSignature],
        yields: Vec<(usize, &'static str)>,
        exceptions: Vec<(usize, &'static str)>,
    ) -> Events {
        let at = |table: &[(usize, &'static str)], name: &str| {
            // a name of no symbol (never so in generated glue) matches no address
            table
                .iter()
                .find(|(_, n)| *n == name)
                .map_or(usize::MAX, |&(a, _)| a)
        };
        let declared = codels
            .iter()
            .map(|sig| {
                sig.yields
                    .iter()
                    .map(|y| at(&yields, y))
                    .chain(sig.throws.iter().map(|e| at(&exceptions, e)))
                    .collect()
            })
            .collect();
        Events {
            declared,
            yields,
            exceptions,
        }
    }

    /// What `ev`, returned by codel `k` of the module object (`sig`), is to the engine:
    /// its declared outcome; a yield or exception of the component it does not declare,
    /// by name (the engine's fault says which); anything else (`genom_ok` from an
    /// activity's codel, an address of no event) an outcome past the declared ones. All
    /// but the first take the activity's error path.
    #[inline]
    pub fn next(&self, k: usize, sig: &CodelSignature, ev: GenomEvent) -> Next {
        let at = ev as usize;
        if let Some(d) = self.declared.get(k) {
            if let Some(i) = d.iter().position(|&a| a == at) {
                return Next::Declared(i as u16);
            }
        }
        self.undeclared(sig, at)
    }

    #[cold]
    fn undeclared(&self, sig: &CodelSignature, at: usize) -> Next {
        let named =
            |table: &[(usize, &'static str)]| table.iter().find(|(a, _)| *a == at).map(|&(_, n)| n);
        if let Some(y) = named(&self.yields) {
            return match sig.yields.iter().position(|d| *d == y) {
                Some(k) => Next::Declared(k as u16),
                None => Next::Yield(y),
            };
        }
        if let Some(e) = named(&self.exceptions) {
            return match sig.throws.iter().position(|d| *d == e) {
                Some(k) => Next::Declared((sig.yields.len() + k) as u16),
                None => Next::Throw(e),
            };
        }
        Next::Declared(u16::MAX)
    }
}
