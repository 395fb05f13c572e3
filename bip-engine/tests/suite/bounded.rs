//! `Bounded<LO, HI>`, the generated bindings' type of a model's `Int(LO, HI)`: only values
//! in the range are made, and it reads as the number it holds.

use std::collections::HashSet;

use bip_engine::{Bounded, OutOfRange};

type Packets = Bounded<1, 10>;
type Offset = Bounded<-5, 5>;

#[test]
fn new_makes_only_values_in_the_range() {
    assert_eq!(Packets::new(1).map(Bounded::get), Some(1));
    assert_eq!(Packets::new(10).map(Bounded::get), Some(10));
    assert_eq!(Packets::new(0), None);
    assert_eq!(Packets::new(11), None);
    assert_eq!(Offset::new(-5).map(Bounded::get), Some(-5));
    assert_eq!(Offset::new(-6), None);
    assert_eq!(
        Bounded::<{ i64::MIN }, { i64::MAX }>::new(i64::MIN).map(Bounded::get),
        Some(i64::MIN)
    );
}

#[test]
fn of_is_a_constant_in_the_range() {
    const THREE: Packets = Packets::of::<3>();
    assert_eq!(THREE.get(), 3);
    assert_eq!(Offset::of::<-5>(), Offset::MIN);
}

#[test]
fn try_from_says_the_value_and_the_range() {
    assert_eq!(Packets::try_from(4).map(i64::from), Ok(4));
    let err = Packets::try_from(12).expect_err("12 > 10");
    assert_eq!(
        err,
        OutOfRange {
            value: 12,
            lo: 1,
            hi: 10
        }
    );
    assert_eq!(
        err.to_string(),
        "12 is out of the range 1..=10 (Int(1, 10))"
    );
    let boxed: Box<dyn std::error::Error> = Box::new(err);
    assert!(boxed.to_string().contains("12"));
}

#[test]
fn min_max_and_saturating_stay_in_the_range() {
    assert_eq!((Packets::MIN.get(), Packets::MAX.get()), (1, 10));
    assert_eq!(Packets::saturating(-3), Packets::MIN);
    assert_eq!(Packets::saturating(99), Packets::MAX);
    assert_eq!(Packets::saturating(7).get(), 7);
}

#[test]
fn the_default_is_zero_if_in_range_else_lo() {
    assert_eq!(Packets::default().get(), 1);
    assert_eq!(Offset::default().get(), 0);
    assert_eq!(Bounded::<-9, -2>::default().get(), -9);
}

#[test]
fn it_compares_hashes_and_prints_as_its_number() {
    let (two, three) = (Packets::of::<2>(), Packets::of::<3>());
    assert!(two < three && two == Packets::of::<2>());
    assert_eq!(two.cmp(&Packets::MAX), std::cmp::Ordering::Less);
    assert_eq!(two.max(three), three);
    let set: HashSet<Packets> = [two, three, two].into_iter().collect();
    assert_eq!(set.len(), 2);
    assert_eq!(format!("{three}"), "3");
    assert_eq!(format!("{:?}", Offset::of::<-4>()), "-4");
    assert_eq!(format!("{:>3}", three), "  3");
}
