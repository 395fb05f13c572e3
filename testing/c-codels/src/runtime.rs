//! What bip gives a C codel at run time, in GenoM3's C API (the `genom3/c` headers
//! bip-codegen writes): the `genom_context` a codel takes last, whose `raise` records the
//! exception a codel throws with a copy of its detail; and the reading of the
//! `genom_event` a codel returns as the engine's [`Next`]. An event is a pointer to its
//! name, defined once by the linker (weak), so it is recognised by its address alone: the
//! engine never reads through a pointer a codel returns, which may be garbage.

use std::ffi::{c_char, c_void};
use std::sync::{Arc, Mutex};

use bip_engine::{CodelSignature, Next};

/// GenoM3's `genom_event`: a pointer to the event's name, NULL for `genom_ok`.
pub type GenomEvent = *const c_char;

/// `struct genom_context_iface` of `genom3/c/context.h`.
#[repr(C)]
pub struct ContextIface {
    raise: unsafe extern "C" fn(GenomEvent, *mut c_void, usize, *const ContextIface) -> GenomEvent,
    raised: unsafe extern "C" fn(*mut GenomEvent, *const ContextIface) -> *const c_void,
    /// The engine's [`Raised`], opaque to C (`struct genom_context_data *`).
    data: *const c_void,
}

/// The exception a codel raised last, as `raise` recorded it: its event (as an address)
/// and a copy of its detail.
#[derive(Debug, Default)]
pub struct Raised(Mutex<Option<(usize, Vec<u8>)>>);

impl Raised {
    /// The last exception's event address and detail bytes, if any.
    pub fn last(&self) -> Option<(usize, Vec<u8>)> {
        self.0.lock().map(|g| g.clone()).unwrap_or(None)
    }
}

unsafe extern "C" fn raise(
    ex: GenomEvent,
    detail: *mut c_void,
    size: usize,
    this: *const ContextIface,
) -> GenomEvent {
    // SAFETY: `this` is the context the engine passed the codel, alive for the call; the
    // codel passes its detail and the detail's size (`sizeof(*d)`), as the generated
    // throwing functions do.
    let bytes = if detail.is_null() || size == 0 {
        Vec::new()
    } else {
        unsafe { std::slice::from_raw_parts(detail as *const u8, size) }.to_vec()
    };
    if let Some(data) =
        unsafe { this.as_ref() }.and_then(|c| unsafe { (c.data as *const Raised).as_ref() })
    {
        if let Ok(mut g) = data.0.lock() {
            *g = Some((ex as usize, bytes));
        }
    }
    ex
}

unsafe extern "C" fn last_raised(ex: *mut GenomEvent, this: *const ContextIface) -> *const c_void {
    // SAFETY: as in `raise`; the detail's bytes stay where they are until the next raise
    // (the lock is released, the vector is not touched).
    let Some(data) =
        (unsafe { this.as_ref() }).and_then(|c| unsafe { (c.data as *const Raised).as_ref() })
    else {
        return std::ptr::null();
    };
    let Ok(g) = data.0.lock() else {
        return std::ptr::null();
    };
    match &*g {
        Some((e, detail)) => {
            if !ex.is_null() {
                unsafe { *ex = *e as GenomEvent };
            }
            detail.as_ptr() as *const c_void
        }
        None => std::ptr::null(),
    }
}

/// The context given to a component's codels: one per module object, at a fixed address.
pub struct Context {
    iface: Box<ContextIface>,
    raised: Arc<Raised>,
}

// SAFETY: the context's pointers are to its own boxed data; the engine calls one codel at
// a time, so the C side never sees it from two threads at once.
unsafe impl Send for Context {}

impl Default for Context {
    fn default() -> Self {
        let raised = Arc::new(Raised::default());
        let iface = Box::new(ContextIface {
            raise,
            raised: last_raised,
            data: Arc::as_ptr(&raised) as *const c_void,
        });
        Context { iface, raised }
    }
}

impl Context {
    /// What a codel takes as `const genom_context self`.
    pub fn as_ptr(&self) -> *const ContextIface {
        &*self.iface
    }

    /// What codels raised, to be read from outside the engine.
    pub fn raised(&self) -> Arc<Raised> {
        Arc::clone(&self.raised)
    }
}

/// A component's events and exceptions: the address of each C symbol with its name in
/// the model (`pause::step`, `e_limit`).
pub struct Events {
    pub yields: Vec<(usize, &'static str)>,
    pub exceptions: Vec<(usize, &'static str)>,
}

impl Events {
    /// What `ev`, returned by the codel `sig` names, is to the engine: its declared
    /// outcome `k` (its yields, then its exceptions); a yield or exception of the
    /// component it does not declare, by name (the engine's fault says which); anything
    /// else (`genom_ok` from an activity's codel, an address of no event) an outcome past
    /// the declared ones. All but the first take the activity's error path.
    pub fn next(&self, sig: &CodelSignature, ev: GenomEvent) -> Next {
        let at = ev as usize;
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
