//! The ids struct the C codels write is the memory the Rust side reads: gcc's layout of
//! `counter_ids` is the mirror's, and values a codel writes are read back as written.

use std::mem::{align_of, offset_of, size_of};

use bip_c_codels::counter::ids as CounterIds;
use bip_c_codels::hooks::counter_ids_layout;

#[test]
fn the_mirror_of_the_ids_has_gccs_layout() {
    // SAFETY: a pure function of codels/counter.c
    let c = |k| unsafe { counter_ids_layout(k) };
    assert_eq!(c(0), size_of::<CounterIds>());
    assert_eq!(c(1), align_of::<CounterIds>());
    assert_eq!(c(2), offset_of!(CounterIds, count));
    assert_eq!(c(3), offset_of!(CounterIds, done));
    assert_eq!(c(4), offset_of!(CounterIds, gain));
    assert_eq!(c(5), offset_of!(CounterIds, at));
}

/// Each generated mirror of mirrors.gen's types has the size, alignment and member
/// offsets bip-codegen gives the C type (`CTypes::layout`, checked against gcc in
/// codegen's tests), and the Rust path of its IDL name.
#[test]
fn every_kind_of_mirror_has_the_c_layout() {
    use bip_c_codels::mirrors_types as m;
    use bip_codegen::c::ctype::CType;

    let gen = std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/mirrors.gen"));
    let spec = bip_lang::read_gen_file(gen, &[]).expect("reads");
    let types = bip_codegen::c::c_types(&spec, &spec.components[0]).expect("C types");
    let check = |key: &str, size: usize, align: usize, offsets: &[(&str, usize)]| {
        let t = CType::Named(key.to_string());
        let l = types.layout(&t).expect("a layout");
        assert_eq!((l.size, l.align), (size as u64, align as u64), "{key}");
        if !offsets.is_empty() {
            let c: Vec<(String, u64)> = types.offsets(&t).expect("offsets");
            let rust: Vec<(String, u64)> = offsets
                .iter()
                .map(|(n, o)| (n.to_string(), *o as u64))
                .collect();
            assert_eq!(c, rust, "{key}");
        }
    };
    macro_rules! layout {
        ($key:expr, $t:ty) => {
            check($key, size_of::<$t>(), align_of::<$t>(), &[])
        };
        ($key:expr, $t:ty, $($f:ident),+) => {
            check(
                $key,
                size_of::<$t>(),
                align_of::<$t>(),
                &[$((stringify!($f), offset_of!($t, $f))),+],
            )
        };
    }
    layout!("geo::point", m::geo::point, x, y);
    layout!("geo::mode", m::geo::mode);
    layout!("geo::path", m::geo::path);
    layout!("geo::reading", m::geo::reading, _d, _u);
    layout!("mirrors::e_far", m::mirrors::e_far_detail);
    layout!(
        "mirrors::ids",
        m::mirrors::ids,
        here,
        mode,
        route,
        last,
        label,
        name,
        marks,
        counts,
        maybe,
        tag,
        on,
        big,
        wide,
        limits
    );
    layout!("mirrors::ids::limits_s", m::mirrors::ids_::limits_s, lo, hi);
}

extern "C" {
    fn counter_test_long_doubles(out: *mut bip_genom_c::LongDouble);
    fn counter_test_long_double_is(x: *const bip_genom_c::LongDouble, want: f64) -> i32;
}

#[test]
fn a_long_double_is_read_and_written_as_gcc_lays_it() {
    let mut got = [bip_genom_c::LongDouble::default(); 4];
    // SAFETY: the C function writes four long doubles, the mirror's layout (checked above)
    unsafe { counter_test_long_doubles(got.as_mut_ptr()) };
    let want = [1.0, -2.5, 1.0 / 3.0, 1e300];
    let read: Vec<f64> = got.iter().map(bip_genom_c::LongDouble::to_f64).collect();
    assert_eq!(read, want);
    for x in want.into_iter().chain([0.0, -5e-324, f64::MAX]) {
        let ld = bip_genom_c::LongDouble::from_f64(x);
        // SAFETY: a pointer to one long double
        assert_eq!(unsafe { counter_test_long_double_is(&ld, x) }, 1, "{x}");
    }
}
