//! C's `long double` where Rust has none: its bytes, of its C layout, on the targets whose
//! layout bip-codegen knows (x86_64's x87 extended precision and aarch64's IEEE binary128,
//! both 16 bytes aligned on 16), with the conversions from and to an `f64`, which is the
//! model's `Float` (rounded to nearest, as C's conversion rounds).

/// A C `long double`, as its bytes.
#[repr(C, align(16))]
#[derive(Clone, Copy, Default, PartialEq)]
pub struct LongDouble(pub [u8; 16]);

impl core::fmt::Debug for LongDouble {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{}L", self.to_f64())
    }
}

/// The exponent bias of both formats (15 bits of exponent).
const BIAS: i32 = 16383;

/// `x * 2^k`, exact but for the ends of `f64`'s range.
fn scale(mut x: f64, mut k: i32) -> f64 {
    let step = |e: i32| f64::from_bits(((e + 1023) as u64) << 52);
    while k > 1000 {
        x *= step(1000);
        k -= 1000;
    }
    while k < -1000 {
        x *= step(-1000);
        k += 1000;
    }
    x * step(k)
}

/// The sign, the unbiased exponent and the 53-bit significand (its leading 1 at bit 52)
/// of a finite, non-zero `x`.
fn parts(x: f64) -> (bool, i32, u64) {
    let bits = x.to_bits();
    let sign = bits >> 63 == 1;
    let e = ((bits >> 52) & 0x7ff) as i32;
    let frac = bits & ((1 << 52) - 1);
    if e == 0 {
        // subnormal: normalise
        let shift = frac.leading_zeros() as i32 - 11;
        (sign, -1022 - shift, frac << shift)
    } else {
        (sign, e - 1023, frac | (1 << 52))
    }
}

impl LongDouble {
    /// x87's 80-bit extended format: 64 bits of significand (its integer bit explicit),
    /// then the sign and 15 bits of exponent.
    pub fn from_f64_x87(x: f64) -> LongDouble {
        let mut b = [0u8; 16];
        let sign = u16::from(x.is_sign_negative()) << 15;
        let (se, mant) = if x == 0.0 {
            (sign, 0u64)
        } else if x.is_infinite() {
            (sign | 0x7fff, 1 << 63)
        } else if x.is_nan() {
            (sign | 0x7fff, 0xc000_0000_0000_0000)
        } else {
            let (_, e, m) = parts(x);
            (sign | (e + BIAS) as u16, m << 11)
        };
        b[..8].copy_from_slice(&mant.to_le_bytes());
        b[8..10].copy_from_slice(&se.to_le_bytes());
        LongDouble(b)
    }

    pub fn to_f64_x87(&self) -> f64 {
        let mut m = [0u8; 8];
        m.copy_from_slice(&self.0[..8]);
        let mant = u64::from_le_bytes(m);
        let se = u16::from_le_bytes([self.0[8], self.0[9]]);
        let sign = if se >> 15 == 1 { -1.0 } else { 1.0 };
        let e = i32::from(se & 0x7fff);
        if e == 0x7fff {
            return if mant << 1 == 0 {
                sign * f64::INFINITY
            } else {
                f64::NAN
            };
        }
        // a denormal's exponent is that of the smallest normal
        sign * scale(mant as f64, e.max(1) - BIAS - 63)
    }

    /// IEEE binary128: 112 bits of fraction, 15 bits of exponent, the sign.
    pub fn from_f64_quad(x: f64) -> LongDouble {
        let sign = u128::from(x.is_sign_negative()) << 127;
        let bits = if x == 0.0 {
            sign
        } else if x.is_infinite() {
            sign | (0x7fff << 112)
        } else if x.is_nan() {
            sign | (0x7fff << 112) | (1 << 111)
        } else {
            let (_, e, m) = parts(x);
            let frac = u128::from(m & ((1 << 52) - 1)) << 60;
            sign | ((((e + BIAS) as u128) & 0x7fff) << 112) | frac
        };
        LongDouble(bits.to_le_bytes())
    }

    pub fn to_f64_quad(&self) -> f64 {
        let bits = u128::from_le_bytes(self.0);
        let sign = if bits >> 127 == 1 { -1.0 } else { 1.0 };
        let e = ((bits >> 112) & 0x7fff) as i32;
        let frac = bits & ((1 << 112) - 1);
        if e == 0x7fff {
            return if frac == 0 {
                sign * f64::INFINITY
            } else {
                f64::NAN
            };
        }
        let (mant, e) = if e == 0 {
            (frac, 1)
        } else {
            (frac | (1 << 112), e)
        };
        // u128 to f64 rounds to nearest
        sign * scale(mant as f64, e - BIAS - 112)
    }

    /// `x` as this target's `long double`.
    pub fn from_f64(x: f64) -> LongDouble {
        if cfg!(target_arch = "aarch64") {
            LongDouble::from_f64_quad(x)
        } else {
            LongDouble::from_f64_x87(x)
        }
    }

    /// This target's `long double` as the nearest `f64`.
    pub fn to_f64(&self) -> f64 {
        if cfg!(target_arch = "aarch64") {
            self.to_f64_quad()
        } else {
            self.to_f64_x87()
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const VALUES: [f64; 9] = [
        1.0,
        -2.5,
        1e300,
        -1e-300,
        5e-324,
        f64::MAX,
        f64::MIN_POSITIVE,
        1.0 / 3.0,
        0.0,
    ];

    #[test]
    fn both_formats_hold_every_f64_exactly() {
        for x in VALUES {
            assert_eq!(LongDouble::from_f64_x87(x).to_f64_x87(), x);
            assert_eq!(LongDouble::from_f64_quad(x).to_f64_quad(), x);
        }
        for x in [f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(LongDouble::from_f64_x87(x).to_f64_x87(), x);
            assert_eq!(LongDouble::from_f64_quad(x).to_f64_quad(), x);
        }
        assert!(LongDouble::from_f64_x87(f64::NAN).to_f64_x87().is_nan());
        assert!(LongDouble::from_f64_quad(f64::NAN).to_f64_quad().is_nan());
    }

    #[test]
    fn one_is_encoded_as_each_format_writes_it() {
        // x87: integer bit set, exponent 0x3fff; binary128: exponent 0x3fff, no fraction
        let x87 = LongDouble::from_f64_x87(1.0).0;
        assert_eq!(&x87[..10], &[0, 0, 0, 0, 0, 0, 0, 0x80, 0xff, 0x3f]);
        let quad = LongDouble::from_f64_quad(-1.0).0;
        assert_eq!(&quad[14..], &[0xff, 0xbf]);
        assert!(quad[..14].iter().all(|&b| b == 0));
    }

    #[test]
    fn more_precision_rounds_to_nearest() {
        // 1 + 2^-60: below half an f64 ulp above 1
        let mut x = LongDouble::from_f64_x87(1.0);
        x.0[0] = 0x08;
        assert_eq!(x.to_f64_x87(), 1.0);
        // 1 + 2^-52 + 2^-53 + 2^-63: past the half between 1 + 2^-52 and 1 + 2^-51
        let mut y = LongDouble::from_f64_x87(1.0);
        y.0[..8].copy_from_slice(&((1u64 << 63) | (1 << 11) | (1 << 10) | 1).to_le_bytes());
        assert_eq!(y.to_f64_x87(), 1.0 + f64::EPSILON * 2.0);
    }
}
