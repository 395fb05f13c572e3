//! [`Bounded`]: a model's `Int(lo, hi)` as a Rust type, so that a value out of its range
//! cannot be written where generated bindings (docs/codegen.md) take one. The engine keeps
//! such values as `i64` (its run-time checks see the range); `Bounded` is the typed API's
//! boundary, converted to `i64` when it enters the engine.

use core::fmt;

/// An integer in `LO..=HI`, both bounds included: the model's `Int(LO, HI)`.
///
/// ```
/// use bip_engine::Bounded;
/// type Packets = Bounded<1, 10>;
/// let three = Packets::of::<3>(); // checked by the compiler
/// assert_eq!(three.get(), 3);
/// assert_eq!(Packets::new(11), None); // checked at run time
/// assert!(Packets::try_from(0).is_err());
/// assert_eq!(i64::from(Packets::MAX), 10);
/// ```
///
/// An out-of-range constant does not compile:
///
/// ```compile_fail
/// let _ = bip_engine::Bounded::<1, 10>::of::<11>();
/// ```
#[derive(Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Bounded<const LO: i64, const HI: i64>(i64);

impl<const LO: i64, const HI: i64> Bounded<LO, HI> {
    /// The least value, `LO`.
    pub const MIN: Self = Self(LO);
    /// The greatest value, `HI`.
    pub const MAX: Self = Self(HI);

    /// `value`, if it is in `LO..=HI`.
    pub const fn new(value: i64) -> Option<Self> {
        if LO <= value && value <= HI {
            Some(Self(value))
        } else {
            None
        }
    }

    /// The constant `V`, which the compiler checks is in `LO..=HI`: out of range, the
    /// build fails where the function that names it is compiled to code (`cargo build`;
    /// `cargo check` does not get that far), or at once in a `const` item.
    pub const fn of<const V: i64>() -> Self {
        const {
            assert!(
                LO <= V && V <= HI,
                "Bounded::<LO, HI>::of::<V>(): V is out of the range LO..=HI"
            )
        };
        Self(V)
    }

    /// `value` moved into `LO..=HI`: `LO` below it, `HI` above it.
    pub const fn saturating(value: i64) -> Self {
        if value < LO {
            Self(LO)
        } else if value > HI {
            Self(HI)
        } else {
            Self(value)
        }
    }

    /// The value, in `LO..=HI`.
    pub const fn get(self) -> i64 {
        self.0
    }
}

impl<const LO: i64, const HI: i64> Default for Bounded<LO, HI> {
    /// 0 if the range holds it, else `LO` (the model's default of an `Int` variable).
    fn default() -> Self {
        const { assert!(LO <= HI, "Bounded::<LO, HI>: the range LO..=HI is empty") };
        match Self::new(0) {
            Some(zero) => zero,
            None => Self(LO),
        }
    }
}

impl<const LO: i64, const HI: i64> fmt::Debug for Bounded<LO, HI> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Debug::fmt(&self.0, f)
    }
}

impl<const LO: i64, const HI: i64> fmt::Display for Bounded<LO, HI> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        fmt::Display::fmt(&self.0, f)
    }
}

impl<const LO: i64, const HI: i64> From<Bounded<LO, HI>> for i64 {
    fn from(value: Bounded<LO, HI>) -> i64 {
        value.0
    }
}

impl<const LO: i64, const HI: i64> TryFrom<i64> for Bounded<LO, HI> {
    type Error = OutOfRange;

    fn try_from(value: i64) -> Result<Self, OutOfRange> {
        Self::new(value).ok_or(OutOfRange {
            value,
            lo: LO,
            hi: HI,
        })
    }
}

/// A value given for a [`Bounded`] outside its range.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OutOfRange {
    pub value: i64,
    pub lo: i64,
    pub hi: i64,
}

impl fmt::Display for OutOfRange {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} is out of the range {}..={} (Int({}, {}))",
            self.value, self.lo, self.hi, self.lo, self.hi
        )
    }
}

impl core::error::Error for OutOfRange {}
