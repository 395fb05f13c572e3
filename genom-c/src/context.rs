//! GenoM3's `genom_context` on the Rust side (`struct genom_context_iface` of the
//! `genom3/c/context.h` header bip-codegen writes): `raise` records the exception a codel
//! throws with a copy of its detail, `raised` gives it back; its opaque `data` also holds
//! the call the engine is making, which the generated port handles' functions reach
//! through the context a codel passes them (they take nothing else).

use std::cell::Cell;
use std::ffi::{c_char, c_void};
use std::sync::{Arc, Mutex};

/// GenoM3's `genom_event`: a pointer to the event's name, NULL for `genom_ok`.
pub type GenomEvent = *const c_char;

/// `struct genom_context_iface`.
#[repr(C)]
pub struct ContextIface {
    raise: unsafe extern "C" fn(GenomEvent, *mut c_void, usize, *const ContextIface) -> GenomEvent,
    raised: unsafe extern "C" fn(*mut GenomEvent, *const ContextIface) -> *const c_void,
    /// The context's [`Data`], opaque to C (`struct genom_context_data *`).
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

/// What `data` points to.
struct Data {
    raised: Arc<Raised>,
    /// The glue's call in progress (null between calls).
    call: Cell<*mut c_void>,
}

/// The context's data, if `this` is a context this crate made.
///
/// # Safety
/// `this` is null or a context given by [`Context::as_ptr`], still alive.
unsafe fn data<'a>(this: *const ContextIface) -> Option<&'a Data> {
    let iface = unsafe { this.as_ref() }?;
    unsafe { (iface.data as *const Data).as_ref() }
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
    if let Some(data) = unsafe { data(this) } {
        if let Ok(mut g) = data.raised.0.lock() {
            *g = Some((ex as usize, bytes));
        }
    }
    ex
}

unsafe extern "C" fn last_raised(ex: *mut GenomEvent, this: *const ContextIface) -> *const c_void {
    // SAFETY: as in `raise`; the detail's bytes stay where they are until the next raise
    // (the lock is released, the vector is not touched).
    let Some(data) = (unsafe { data(this) }) else {
        return std::ptr::null();
    };
    let Ok(g) = data.raised.0.lock() else {
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
    data: Box<Data>,
}

// SAFETY: the context's pointers are to its own boxed data; the engine calls one codel of
// a module object at a time, and an async codel, which runs beside them, has a context of
// its own ([`Context::beside`]), so the C side never sees one from two threads at once.
unsafe impl Send for Context {}

impl Default for Context {
    fn default() -> Self {
        Context::raising_into(Arc::new(Raised::default()))
    }
}

impl Context {
    fn raising_into(raised: Arc<Raised>) -> Self {
        let data = Box::new(Data {
            raised,
            call: Cell::new(std::ptr::null_mut()),
        });
        let iface = Box::new(ContextIface {
            raise,
            raised: last_raised,
            data: &*data as *const Data as *const c_void,
        });
        Context { iface, data }
    }

    /// A context for a codel that runs beside those of this one (an async codel, on a
    /// thread of its own): its own call in progress, and what it raises kept with what
    /// this one's codels raise ([`Context::raised`]).
    pub fn beside(&self) -> Context {
        Context::raising_into(Arc::clone(&self.data.raised))
    }
}

impl Context {
    /// What a codel takes as `const genom_context self`.
    pub fn as_ptr(&self) -> *const ContextIface {
        &*self.iface
    }

    /// What codels raised, to be read from outside the engine.
    pub fn raised(&self) -> Arc<Raised> {
        Arc::clone(&self.data.raised)
    }

    /// Runs `f` with `call` as the call in progress, which [`call`] gives back from the
    /// context while `f` runs (a codel calling a port handle's function), and null after.
    pub fn with_call<R>(&self, call: *mut c_void, f: impl FnOnce() -> R) -> R {
        self.data.call.set(call);
        let r = f();
        self.data.call.set(std::ptr::null_mut());
        r
    }
}

/// The call in progress on context `this` (what [`Context::with_call`] was given), as a
/// `T`; `None` outside a call or for a context this crate did not make.
///
/// # Safety
/// `this` is null or a context given by [`Context::as_ptr`], still alive, and the call in
/// progress was given as a `*mut T`.
pub unsafe fn call<T>(this: *const ContextIface) -> Option<*mut T> {
    let c = unsafe { data(this) }?.call.get();
    (!c.is_null()).then_some(c as *mut T)
}

/// Raises exception `ex` with `detail` on context `this`, as a codel's throwing function
/// does, and returns `ex`: what the glue's port functions return when they fail.
///
/// # Safety
/// `this` is null or a context given by [`Context::as_ptr`], still alive.
pub unsafe fn throw(this: *const ContextIface, ex: GenomEvent, detail: &[u8]) -> GenomEvent {
    // SAFETY: `raise` copies the detail's bytes and keeps no pointer to them
    unsafe { raise(ex, detail.as_ptr() as *mut c_void, detail.len(), this) }
}
