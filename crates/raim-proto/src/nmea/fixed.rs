//! Decimal text of integers and of f64 values with a fixed number of
//! decimals, in integer arithmetic, for the NMEA writer (flash).
//!
//! Why not `core::fmt`: its float formatting (Grisu with a Dragon4
//! fallback, big-number tables) is ~12 KB of the firmware's flash, and
//! integer `write!` pulls in the formatter machinery too. The output here
//! is the same text, byte for byte, as `format!("{v:.prec$}")` and
//! `format!("{n:0width$}")`: the exact binary value of `v` rounded to
//! `prec` decimals, ties to even, with a `-` for any negative value
//! (including `-0.0` and values that round to zero). The tests check
//! that against `format!` on every kind of value: exact ties, subnormals,
//! the largest finite values, and a few hundred thousand pseudo-random ones.

use core::fmt::{Result, Write};

/// 10^9, the chunk of the big-integer printer.
const CHUNK: u64 = 1_000_000_000;

/// Limbs of an f64's integer value: the largest finite f64 is below 2^1024.
const LIMBS: usize = 1024 / 32;

/// Decimal chunks of 9 digits for the same: 309 digits at most.
const CHUNKS: usize = 35;

/// Powers of ten that fit a u64, for `prec` up to 19.
fn pow10(prec: u32) -> u64 {
    10u64.pow(prec.min(19))
}

/// `n` in decimal, zero-padded on the left to at least `width` digits
/// (`{n:0width$}`).
pub fn uint<W: Write>(w: &mut W, n: u64, width: u32) -> Result {
    let mut digits = 1u32;
    let mut top = 1u64;
    while top <= n / 10 {
        top *= 10;
        digits += 1;
    }
    for _ in digits..width {
        w.write_char('0')?;
    }
    let mut rest = n;
    loop {
        // top >= 1 (a power of ten); the `else` is never taken.
        let Some(d) = rest.checked_div(top) else {
            return Ok(());
        };
        rest -= d * top;
        w.write_char(digit(d))?;
        if top == 1 {
            return Ok(());
        }
        top /= 10;
    }
}

/// The character of a decimal digit 0..=9.
fn digit(d: u64) -> char {
    char::from(b'0' + (d % 10) as u8)
}

/// A finite `v` with `prec` decimals, as `{v:.prec$}` writes it. The
/// caller handles non-finite values (NMEA leaves the field empty).
pub fn decimal<W: Write>(w: &mut W, v: f64, prec: u32) -> Result {
    let bits = v.to_bits();
    if bits >> 63 == 1 {
        w.write_char('-')?;
    }
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let frac = bits & ((1u64 << 52) - 1);
    // v = m * 2^e exactly.
    let (m, e) = if biased == 0 {
        (frac, -1074)
    } else {
        (frac | (1u64 << 52), biased - 1075)
    };
    if e >= 0 {
        // An integer: its digits, then `prec` zeros.
        if e <= 11 {
            uint(w, m << e, 1)?;
        } else {
            big_uint(w, m, e.unsigned_abs())?;
        }
        return zeros(w, prec);
    }
    let k = e.unsigned_abs();
    let (mut int, f) = if k < 64 {
        (m >> k, m & ((1u64 << k) - 1))
    } else {
        (0, m)
    };
    // The fraction f / 2^k scaled by 10^prec and rounded half to even:
    // f * 10^prec < 2^53 * 2^64 fits a u128, and for k >= 118 it is below
    // half of 2^k, so it rounds to zero.
    let scale = pow10(prec);
    let mut frac_digits = 0u64;
    if k < 118 {
        let n = u128::from(f) * u128::from(scale);
        let q = n >> k;
        let r = n - (q << k);
        let half = 1u128 << (k - 1);
        let last_odd = if prec == 0 { int & 1 == 1 } else { q & 1 == 1 };
        // q < 10^prec: f < 2^k.
        frac_digits = q as u64;
        if r > half || (r == half && last_odd) {
            frac_digits += 1;
            if frac_digits == scale {
                frac_digits = 0;
                int += 1;
            }
        }
    }
    uint(w, int, 1)?;
    if prec > 0 {
        w.write_char('.')?;
        uint(w, frac_digits, prec)?;
    }
    Ok(())
}

/// `.` and `prec` zeros (nothing for `prec` 0).
fn zeros<W: Write>(w: &mut W, prec: u32) -> Result {
    if prec > 0 {
        w.write_char('.')?;
        for _ in 0..prec {
            w.write_char('0')?;
        }
    }
    Ok(())
}

/// m * 2^e in decimal, for the integers beyond u64 (e > 11, up to the
/// largest finite f64): 32-bit limbs, divided by 10^9 a chunk at a time.
fn big_uint<W: Write>(w: &mut W, m: u64, e: u32) -> Result {
    let mut limbs = [0u32; LIMBS + 2];
    let (word, bit) = ((e / 32) as usize, e % 32);
    let wide = u128::from(m) << bit;
    for (i, limb) in limbs.iter_mut().skip(word).take(3).enumerate() {
        *limb = (wide >> (32 * i)) as u32;
    }
    let mut chunks = [0u32; CHUNKS];
    let mut used = 0usize;
    for chunk in chunks.iter_mut() {
        let mut rem = 0u64;
        for limb in limbs.iter_mut().rev() {
            let cur = (rem << 32) | u64::from(*limb);
            *limb = (cur / CHUNK) as u32;
            rem = cur % CHUNK;
        }
        *chunk = rem as u32;
        used += 1;
        if limbs.iter().all(|l| *l == 0) {
            break;
        }
    }
    let mut width = 1;
    for chunk in chunks.iter().take(used).rev() {
        uint(w, u64::from(*chunk), width)?;
        width = 9;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use std::format;
    use std::string::String;

    fn ours(v: f64, prec: u32) -> String {
        let mut s = String::new();
        decimal(&mut s, v, prec).unwrap();
        s
    }

    fn check(v: f64) {
        for prec in [0u32, 1, 2, 3, 6] {
            let want = format!("{v:.*}", prec as usize);
            assert_eq!(
                ours(v, prec),
                want,
                "{v:e} ({:#x}) prec {prec}",
                v.to_bits()
            );
        }
    }

    /// xorshift64*: a fixed pseudo-random sequence (no dependency).
    fn next(state: &mut u64) -> u64 {
        *state ^= *state >> 12;
        *state ^= *state << 25;
        *state ^= *state >> 27;
        state.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }

    #[test]
    fn integers_match_core_fmt() {
        for n in [0u64, 1, 9, 10, 99, 100, 12_345, u64::MAX / 10, u64::MAX] {
            for width in [0u32, 1, 2, 3, 6, 20, 22] {
                let mut s = String::new();
                uint(&mut s, n, width).unwrap();
                assert_eq!(s, format!("{n:0w$}", w = width as usize));
            }
        }
    }

    #[test]
    fn special_values_match_core_fmt() {
        for v in [
            0.0,
            -0.0,
            f64::MIN_POSITIVE,
            -f64::MIN_POSITIVE,
            5e-324,
            -5e-324,
            f64::MAX,
            f64::MIN,
            f64::EPSILON,
            1.0,
            -1.0,
            0.5,
            1.5,
            2.5,
            -2.5,
            0.25,
            0.35,
            0.0625,
            0.0005,
            0.9995,
            0.99999949999,
            9.9999995,
            999.9995,
            -0.0004,
            123.4567,
            4_503_599_627_370_496.5,
            9_007_199_254_740_993.0,
            18_446_744_073_709_551_615.0,
            1e30,
            3.4e38,
            f64::from(f32::MAX),
            6_378_137.0,
        ] {
            check(v);
        }
    }

    /// Every multiple of 2^-j near small integers: exact decimal ties at
    /// every precision (x.5, x.25, x.125, ... x.0000005 is not exact, but
    /// x.0000005 +- 1 ulp is checked by the random sweep).
    #[test]
    fn exact_ties_round_to_even_like_core_fmt() {
        for j in 1..=24 {
            let step = 1.0 / f64::from(1u32 << j);
            for i in 0..64 {
                let v = f64::from(i) * step;
                check(v);
                check(-v);
                check(1000.0 + v);
            }
        }
    }

    #[test]
    fn pseudo_random_values_match_core_fmt() {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        for _ in 0..100_000 {
            // Any bit pattern (every exponent, subnormals included)...
            let v = f64::from_bits(next(&mut state));
            if v.is_finite() {
                check(v);
            }
            // ...and the magnitudes NMEA fields carry: 1e-9 .. 1e7.
            let u = (next(&mut state) >> 11) as f64 / (1u64 << 53) as f64;
            let x = libm::pow(10.0, -9.0 + 16.0 * u);
            check(x);
            check(-x);
        }
    }
}
