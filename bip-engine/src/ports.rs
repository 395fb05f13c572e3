//! Port data (GenoM posters): the model tracks only a port's age; the data lives here,
//! one value of any type per out port, written by the module's codels and read by anyone,
//! under its name or under the name of an in port connected to it.
//! A port whose type the model declares takes only values of that type; any port keeps
//! the type of its first value.

use core::any::{type_name, Any};

#[allow(unused_imports)]
use crate::prelude::*;

use bip_model::genom::map::DataType;

/// A port's data: any `Clone` type, so that an async codel can take its own copy of the
/// ports when it starts (docs/engine.md, "Async codels").
pub(crate) trait PortData: Any + Send {
    #[cfg_attr(not(feature = "std"), allow(dead_code))]
    fn copy(&self) -> Box<dyn PortData>;
    fn as_any(&self) -> &dyn Any;
    fn as_any_mut(&mut self) -> &mut dyn Any;
}

impl<T: Any + Send + Clone> PortData for T {
    fn copy(&self) -> Box<dyn PortData> {
        Box::new(self.clone())
    }
    fn as_any(&self) -> &dyn Any {
        self
    }
    fn as_any_mut(&mut self) -> &mut dyn Any {
        self
    }
}

#[derive(Default)]
pub(crate) struct PortStore {
    /// (module, port) names, in the GenoM map's order.
    names: Vec<(String, String)>,
    /// The declared type of each.
    types: Vec<Option<DataType>>,
    /// The value of each, and its Rust type's name.
    values: Vec<Option<(Box<dyn PortData>, &'static str)>>,
    /// (module, in port, entry) per connected in port: reading it reads that entry.
    links: Vec<(String, String, usize)>,
}

/// A value of another type than a port takes: the port (`module.port`), what it takes
/// in words, and the type given.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct WrongType {
    pub port: String,
    pub expected: String,
    pub given: &'static str,
}

impl PortStore {
    pub fn new(
        names: Vec<(String, String)>,
        types: Vec<Option<DataType>>,
        links: Vec<(String, String, usize)>,
    ) -> PortStore {
        let values = names.iter().map(|_| None).collect();
        PortStore {
            names,
            types,
            values,
            links,
        }
    }

    /// The entry of out port `module.port`, or of the out port that in port `module.port`
    /// is connected to.
    pub fn index(&self, module: &str, port: &str) -> Option<usize> {
        self.names
            .iter()
            .position(|(m, p)| m == module && p == port)
            .or_else(|| {
                self.links
                    .iter()
                    .find(|(m, p, _)| m == module && p == port)
                    .map(|l| l.2)
            })
    }

    pub fn get<T: Any>(&self, module: &str, port: &str) -> Option<&T> {
        let k = self.index(module, port)?;
        (*self.values[k].as_ref()?.0).as_any().downcast_ref()
    }

    /// The value at `k` as a `T`: `None` if it has none yet; an error if it holds another
    /// type, or if a `T` is not of the port's declared type.
    pub fn read<T: Any>(&self, k: usize) -> Result<Option<&T>, WrongType> {
        match &self.values[k] {
            Some((v, held)) => match (**v).as_any().downcast_ref() {
                Some(v) => Ok(Some(v)),
                None => Err(self.wrong::<T>(k, held)),
            },
            None => match &self.types[k] {
                Some(ty) if !ty.accepts(type_name::<T>()) => Err(self.wrong::<T>(k, "")),
                _ => Ok(None),
            },
        }
    }

    /// The value at `k` as a `T`, created with `T::default()` on first use (if a `T` is of
    /// the port's declared type); an error if it holds another type.
    pub fn get_mut_or_default<T: Any + Send + Clone + Default>(
        &mut self,
        k: usize,
    ) -> Result<&mut T, WrongType> {
        if self.values[k].is_none() {
            if let Some(ty) = &self.types[k] {
                if !ty.accepts(type_name::<T>()) {
                    return Err(self.wrong::<T>(k, ""));
                }
            }
            self.values[k] = Some((Box::new(T::default()), type_name::<T>()));
        }
        if !self.values[k]
            .as_ref()
            .is_some_and(|v| (*v.0).as_any().is::<T>())
        {
            let held = self.values[k].as_ref().map_or("", |v| v.1);
            return Err(self.wrong::<T>(k, held));
        }
        // (a `T`, as just asked)
        self.values[k]
            .as_mut()
            .and_then(|v| (*v.0).as_any_mut().downcast_mut())
            .ok_or_else(|| WrongType {
                port: String::new(),
                expected: String::new(),
                given: type_name::<T>(),
            })
    }

    /// A copy of the store: each port's data cloned (what an async codel works on).
    #[cfg(feature = "std")]
    pub fn copy(&self) -> PortStore {
        PortStore {
            names: self.names.clone(),
            types: self.types.clone(),
            values: self
                .values
                .iter()
                .map(|v| v.as_ref().map(|(d, held)| ((**d).copy(), *held)))
                .collect(),
            links: self.links.clone(),
        }
    }

    /// Moves the data of port `k` of `from` here (an async codel's write, committed).
    #[cfg(feature = "std")]
    pub fn take_from(&mut self, from: &mut PortStore, k: usize) {
        if let (Some(to), Some(Some(v))) = (
            self.values.get_mut(k),
            from.values.get_mut(k).map(Option::take),
        ) {
            *to = Some(v);
        }
    }

    /// What port `k` takes, against a `T` given: its declared type, else the type it
    /// holds (`held`).
    #[cold]
    fn wrong<T>(&self, k: usize, held: &str) -> WrongType {
        let expected = match &self.types[k] {
            Some(ty) => format!("{ty} (a Rust `{}`)", ty.rust_name()),
            None => format!("a `{held}`, the type it holds"),
        };
        let (m, p) = &self.names[k];
        WrongType {
            port: format!("{m}.{p}"),
            expected,
            given: type_name::<T>(),
        }
    }
}

impl core::fmt::Debug for PortStore {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        f.debug_list()
            .entries(
                self.names
                    .iter()
                    .zip(&self.values)
                    .map(|((m, p), v)| (m, p, v.as_ref().map(|v| v.1))),
            )
            .finish()
    }
}
