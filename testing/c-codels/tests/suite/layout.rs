//! The ids struct the C codels write is the memory the Rust side reads: gcc's layout of
//! `counter_ids` is the mirror's, and values a codel writes are read back as written.

use std::mem::{align_of, offset_of, size_of};

use bip_c_codels::counter::{counter_ids_layout, CounterIds};

#[test]
fn the_mirror_of_the_ids_has_gccs_layout() {
    // SAFETY: a pure function of codels/counter.c
    let c = |k| unsafe { counter_ids_layout(k) };
    assert_eq!(c(0), size_of::<CounterIds>());
    assert_eq!(c(1), align_of::<CounterIds>());
    assert_eq!(c(2), offset_of!(CounterIds, count));
    assert_eq!(c(3), offset_of!(CounterIds, done));
    assert_eq!(c(4), offset_of!(CounterIds, gain));
}
