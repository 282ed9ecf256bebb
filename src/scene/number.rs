//! Numbers as the text readers write them: `parse_f32` gives exactly the `f32` that
//! `str::parse` gives, with a fast path for the plain decimals that make up the bulk of
//! every scene. Apart from the tokenizer (`lex`) because it is pure arithmetic on bytes.

/// Exact powers of ten as f64 (all up to 1e22 are exactly representable).
const POW10: [f64; 23] = [
    1e0, 1e1, 1e2, 1e3, 1e4, 1e5, 1e6, 1e7, 1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15, 1e16,
    1e17, 1e18, 1e19, 1e20, 1e21, 1e22,
];

/// Parses a number token; `None` when it is not a number at all.
///
/// Gives exactly the `f32` that `str::parse::<f32>` gives (a unit test compares them over
/// many values). Plain decimals, the bulk of every scene, take a fast path; anything else
/// (long mantissas, big exponents, `inf`, `nan`, odd spellings) goes to `str::parse`.
#[inline]
pub fn parse_f32(text: &[u8]) -> Option<f32> {
    match fast_f32(text) {
        Some(v) => Some(v),
        // `str::parse` accepts "inf"/"nan" spelled out; callers reject non-finite values with
        // a message of their own.
        None => std::str::from_utf8(text).ok()?.parse::<f32>().ok(),
    }
}

/// Clinger's fast path, in f64: a mantissa below 2^53 and a power of ten up to 22 are both
/// exact in f64, so one multiplication or division rounds correctly. Rounding that f64 to f32
/// is then the correct f32 too, unless the f64 landed exactly on the midpoint between two
/// f32s (double rounding): that case, and every input the grammar below does not cover,
/// returns `None` for the slow path.
#[inline]
fn fast_f32(t: &[u8]) -> Option<f32> {
    let mut i = 0;
    let neg = match t.first()? {
        b'-' => {
            i = 1;
            true
        }
        b'+' => {
            i = 1;
            false
        }
        _ => false,
    };
    let mut mant: u64 = 0;
    let mut digits = 0usize; // significant digits accumulated (leading zeros excluded)
    let mut any_digit = false;
    let mut exp: i64 = 0;
    // Digits with at most one '.' among them; each digit after it lowers the exponent.
    let mut after_dot = false;
    while let Some(&b) = t.get(i) {
        if b == b'.' && !after_dot {
            after_dot = true;
            i += 1;
            continue;
        }
        let d = b.wrapping_sub(b'0');
        if d > 9 {
            break;
        }
        any_digit = true;
        if mant != 0 || d != 0 {
            digits += 1;
        }
        mant = mant.wrapping_mul(10).wrapping_add(d as u64);
        exp -= after_dot as i64;
        i += 1;
    }
    // 15 significant digits stay below 2^53 and cannot have wrapped.
    if !any_digit || digits > 15 {
        return None;
    }
    if let Some(&(b'e' | b'E')) = t.get(i) {
        i += 1;
        let eneg = match t.get(i) {
            Some(b'-') => {
                i += 1;
                true
            }
            Some(b'+') => {
                i += 1;
                false
            }
            _ => false,
        };
        let start = i;
        let mut e: i64 = 0;
        while let Some(&b) = t.get(i) {
            let d = b.wrapping_sub(b'0');
            if d > 9 || i - start >= 4 {
                break;
            }
            e = e * 10 + d as i64;
            i += 1;
        }
        if i == start {
            return None;
        }
        exp += if eneg { -e } else { e };
    }
    if i != t.len() {
        return None;
    }
    let v = if mant == 0 {
        0.0
    } else if (0..=22).contains(&exp) {
        mant as f64 * POW10[exp as usize]
    } else if (-22..0).contains(&exp) {
        mant as f64 / POW10[(-exp) as usize]
    } else {
        return None;
    };
    // f64 -> f32 drops 29 mantissa bits; all values here are normal in both types
    // (1e-22 <= |v| < 1e38). A dropped part of exactly one half is a midpoint.
    if v.to_bits() & ((1 << 29) - 1) == 1 << 28 {
        return None;
    }
    let v = v as f32;
    Some(if neg { -v } else { v })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast path must agree bit for bit with `str::parse`, including the sign of zero,
    /// on every spelling: random decimals of every length, exponents near the fast path's
    /// limits, exact f32 midpoints (where double rounding would go wrong) and junk.
    #[test]
    fn fast_float_path_matches_str_parse_exactly() {
        fn check(s: &str) {
            let want = s.parse::<f32>().ok();
            let got = parse_f32(s.as_bytes());
            assert_eq!(
                got.map(f32::to_bits),
                want.map(f32::to_bits),
                "parse of {s:?}: got {got:?}, str::parse gives {want:?}"
            );
        }
        for s in [
            "0",
            "-0",
            "+0",
            "0.0",
            "-0.0",
            "1",
            "1.",
            ".5",
            "-.5",
            "+.5",
            ".",
            "-",
            "+",
            "",
            "e5",
            "1e",
            "1e+",
            "1e-",
            "1E5",
            "1e+5",
            "1e-5",
            "1e0005",
            "1e00005",
            "1.5e-22",
            "1.5e22",
            "9e22",
            "9e23",
            "1e-23",
            "16777216",
            "16777217",
            "16777219",
            "33554435",
            "0.1",
            "0.2",
            "0.3",
            "3.4028235e38",
            "3.4028236e38",
            "1e38",
            "1e39",
            "1e-45",
            "1e-46",
            "1.11022e-16",
            "100000",
            "999999999999999",
            "9999999999999999",
            "0.000000000000000000001",
            "00000000000000000000001",
            "1..2",
            "1.2.3",
            "1e2e3",
            "--1",
            "+-1",
            "0x10",
            "inf",
            "-inf",
            "nan",
            "infinity",
            "NaN",
            "1_0",
            "1 ",
            " 1",
            "1f",
            "١",
        ] {
            check(s);
        }
        // Random decimals: sign, up to 18 integer and fraction digits, optional exponent.
        let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
        let mut next = move || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let mut s = String::new();
        for _ in 0..300_000 {
            s.clear();
            let r = next();
            match r % 3 {
                0 => s.push('-'),
                1 if r % 7 == 0 => s.push('+'),
                _ => {}
            }
            let int_digits = (next() % 12) as usize;
            let frac_digits = (next() % 12) as usize;
            for _ in 0..int_digits {
                s.push((b'0' + (next() % 10) as u8) as char);
            }
            if frac_digits > 0 || next() % 4 == 0 {
                s.push('.');
            }
            for _ in 0..frac_digits {
                s.push((b'0' + (next() % 10) as u8) as char);
            }
            if next() % 3 == 0 {
                s.push(if next() % 2 == 0 { 'e' } else { 'E' });
                match next() % 3 {
                    0 => s.push('-'),
                    1 => s.push('+'),
                    _ => {}
                }
                s.push_str(&(next() % 40).to_string());
            }
            check(&s);
        }
        // Exact midpoints between neighbouring f32s written out in decimal: the f64 fast
        // path computes them exactly and must defer to the slow path's ties-to-even.
        for i in 0..2000u32 {
            let a = f32::from_bits(0x4B80_0000 + i * 977); // >= 2^24: integers, spacing >= 2
            let mid = (a as f64 + f32::from_bits(a.to_bits() + 1) as f64) / 2.0;
            check(&format!("{mid}"));
            let b = f32::from_bits(0x3F80_0000 + i * 4099); // in [1, 2): spacing 2^-23
            let mid = (b as f64 + f32::from_bits(b.to_bits() + 1) as f64) / 2.0;
            check(&format!("{mid}"));
        }
    }
}
