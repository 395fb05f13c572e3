//! Port data (GenoM posters): the model tracks only a port's age; the data lives here,
//! one value of any type per out port, written by the module's codels and read by anyone.

use core::any::Any;

#[allow(unused_imports)]
use crate::prelude::*;

#[derive(Default)]
pub(crate) struct PortStore {
    /// (module, port) names, in the GenoM map's order.
    names: Vec<(String, String)>,
    values: Vec<Option<Box<dyn Any + Send>>>,
}

impl PortStore {
    pub fn new(names: Vec<(String, String)>) -> PortStore {
        let values = names.iter().map(|_| None).collect();
        PortStore { names, values }
    }

    pub fn index(&self, module: &str, port: &str) -> Option<usize> {
        self.names
            .iter()
            .position(|(m, p)| m == module && p == port)
    }

    pub fn get<T: Any>(&self, module: &str, port: &str) -> Option<&T> {
        let k = self.index(module, port)?;
        self.values[k].as_ref()?.downcast_ref()
    }

    /// The value at `k` as a `T`, created on first use; `None` if it holds another type.
    pub fn get_mut_or_default<T: Any + Send + Default>(&mut self, k: usize) -> Option<&mut T> {
        let slot = self.values.get_mut(k)?;
        if slot.is_none() {
            *slot = Some(Box::new(T::default()));
        }
        slot.as_mut()?.downcast_mut()
    }
}

impl core::fmt::Debug for PortStore {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_list()
            .entries(
                self.names
                    .iter()
                    .zip(&self.values)
                    .map(|((m, p), v)| (m, p, v.is_some())),
            )
            .finish()
    }
}
