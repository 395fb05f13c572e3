//! The instances of a GenoM3 `multiple` port, by name, in the module object's memory: a
//! codel opens and closes them (an out port's `open` and `close`), and reaches each by
//! its name through the port handle's `data`, `read` and `write`. Each instance is boxed,
//! so that the pointer `data` gives a codel stays valid while others are opened.

use std::ffi::{CStr, CString};

/// A multiple port's instances, in the order they were opened.
#[derive(Clone, Debug)]
pub struct Instances<T> {
    items: Vec<(CString, Box<T>)>,
}

impl<T> Default for Instances<T> {
    fn default() -> Self {
        Instances { items: Vec::new() }
    }
}

impl<T> Instances<T> {
    fn position(&self, id: &CStr) -> Option<usize> {
        self.items.iter().position(|(n, _)| n.as_c_str() == id)
    }

    /// Instance `id`, if it is open.
    pub fn get(&self, id: &CStr) -> Option<&T> {
        self.position(id).map(|k| &*self.items[k].1)
    }

    pub fn get_mut(&mut self, id: &CStr) -> Option<&mut T> {
        self.position(id).map(|k| &mut *self.items[k].1)
    }

    /// Closes instance `id`; false if it was not open.
    pub fn close(&mut self, id: &CStr) -> bool {
        match self.position(id) {
            Some(k) => {
                self.items.remove(k);
                true
            }
            None => false,
        }
    }

    /// The open instances' names and data, in the order they were opened.
    pub fn iter(&self) -> impl Iterator<Item = (&CStr, &T)> {
        self.items.iter().map(|(n, v)| (n.as_c_str(), &**v))
    }

    pub fn len(&self) -> usize {
        self.items.len()
    }

    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }
}

impl<T: Default> Instances<T> {
    /// Instance `id`, opened (its data the type's default) if it was not.
    pub fn open(&mut self, id: &CStr) -> &mut T {
        let k = match self.position(id) {
            Some(k) => k,
            None => {
                self.items.push((id.to_owned(), Box::default()));
                self.items.len() - 1
            }
        };
        &mut self.items[k].1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn instances_keep_their_place_while_others_open_and_close() {
        let mut m: Instances<f64> = Instances::default();
        *m.open(c"left") = 1.0;
        let at: *const f64 = m.get(c"left").expect("open");
        for k in 0..100 {
            let name = CString::new(format!("i{k}")).expect("no NUL");
            *m.open(&name) = f64::from(k);
        }
        assert!(m.close(c"i3"));
        assert!(!m.close(c"i3"));
        assert_eq!(m.get(c"left").map(|v| v as *const f64), Some(at));
        assert_eq!(m.get(c"i4"), Some(&4.0));
        assert_eq!(m.len(), 100);
        // opening an open instance keeps its data
        assert_eq!(*m.open(c"left"), 1.0);
        let names: Vec<&CStr> = m.iter().map(|(n, _)| n).take(2).collect();
        assert_eq!(names, [c"left", c"i0"]);
    }
}
