//! Every lane operation against the scalar operation it stands for, bit for
//! bit, on random values and the special ones (±0, ±∞, NaN, subnormals,
//! extremes), on every backend the CPU has (the portable one always).

use glam::Vec3;

use super::*;
use epsm_testkit::Rng;

const SPECIAL: [f32; 12] = [
    0.0,
    -0.0,
    1.0,
    -1.0,
    f32::INFINITY,
    f32::NEG_INFINITY,
    f32::NAN,
    f32::MIN_POSITIVE,
    1e-40,
    f32::MAX,
    f32::MIN,
    0.5,
];

/// Sixteen values: specials mixed with random values of random magnitude.
fn values(rng: &mut Rng) -> [f32; LANES] {
    std::array::from_fn(|_| {
        if rng.below(4) == 0 {
            SPECIAL[rng.below(SPECIAL.len())]
        } else {
            (rng.range(-1.0, 1.0) * 10f64.powf(rng.range(-8.0, 8.0))) as f32
        }
    })
}

/// A named lane result and the scalar operation it stands for.
type Case<R, F> = (&'static str, R, F);
/// A unary `f32` case.
type Unary<B> = Case<F32x16<B>, fn(f32) -> f32>;
/// A binary `f32` case.
type Binary<B> = Case<F32x16<B>, fn(f32, f32) -> f32>;
/// An `f32` comparison case.
type Compare = Case<Mask16, fn(f32, f32) -> bool>;
/// A binary `f64` case.
type Binary64<B> = Case<F64x16<B>, fn(f64, f64) -> f64>;

/// Equal bit patterns, or both NaN.
fn same(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

fn same64(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

#[test]
fn f32_lanes_match_scalar_operations() {
    fn on<B: Lanes>(k: B) {
        let mut rng = Rng::new(1);
        for _ in 0..2000 {
            let (a, b) = (values(&mut rng), values(&mut rng));
            let (x, y) = (F32x16::from_array(k, a), F32x16::from_array(k, b));
            let m = Mask16(rng.below(1 << 16) as u16);
            let unary: [Unary<B>; 4] = [
                ("sqrt", x.sqrt(), f32::sqrt),
                ("abs", x.abs(), f32::abs),
                ("neg", -x, |a| -a),
                ("bits", F32x16::from_bits(x.to_bits()), |a| a),
            ];
            for (name, got, f) in unary {
                for (i, g) in got.to_array().into_iter().enumerate() {
                    assert!(same(g, f(a[i])), "{name}({})", a[i]);
                }
            }
            let binary: [Binary<B>; 8] = [
                ("add", x + y, |a, b| a + b),
                ("sub", x - y, |a, b| a - b),
                ("mul", x * y, |a, b| a * b),
                ("div", x / y, |a, b| a / b),
                ("min", x.min(y), |a, b| if a < b { a } else { b }),
                ("max", x.max(y), |a, b| if a > b { a } else { b }),
                ("copysign", x.copysign(y), f32::copysign),
                (
                    "clamp01",
                    x.clamp(F32x16::splat(k, 0.0), F32x16::splat(k, 1.0)),
                    |a, _| a.clamp(0.0, 1.0),
                ),
            ];
            for (name, got, f) in binary {
                for (i, g) in got.to_array().into_iter().enumerate() {
                    assert!(same(g, f(a[i], b[i])), "{name}({}, {})", a[i], b[i]);
                }
            }
            let compares: [Compare; 5] = [
                ("lt", x.lt(y), |a, b| a < b),
                ("le", x.le(y), |a, b| a <= b),
                ("gt", x.gt(y), |a, b| a > b),
                ("ge", x.ge(y), |a, b| a >= b),
                ("eq", x.eq(y), |a, b| a == b),
            ];
            for (name, got, f) in compares {
                for i in 0..LANES {
                    assert_eq!(got.test(i), f(a[i], b[i]), "{name}({}, {})", a[i], b[i]);
                }
            }
            let selected = F32x16::select(m, x, y).to_array();
            let finite = x.is_finite();
            let wide = x.to_f64().to_array();
            for i in 0..LANES {
                assert!(same(selected[i], if m.test(i) { a[i] } else { b[i] }));
                assert_eq!(finite.test(i), a[i].is_finite());
                assert!(same64(wide[i], f64::from(a[i])));
            }
            // Conversions from integers, and truncation within i32's range.
            let u: [u32; LANES] = std::array::from_fn(|_| rng.below(1 << 32) as u32);
            let ux = U32x16::from_array(k, u);
            let from_u = F32x16::from_u32(ux).to_array();
            let small = F32x16::from_array(k, a.map(|v| if v.abs() < 2e9 { v } else { 0.5 }));
            let truncated = small.trunc_i32().to_array();
            for i in 0..LANES {
                assert!(same(from_u[i], u[i] as f32));
                assert_eq!(truncated[i] as i32, small.lane(i) as i32);
            }
        }
    }
    crate::simd::each_backend!(on);
}

#[test]
fn f64_lanes_match_scalar_operations() {
    fn on<B: Lanes>(k: B) {
        let mut rng = Rng::new(2);
        for _ in 0..2000 {
            let (a, b) = (values(&mut rng), values(&mut rng));
            let (a, b) = (a.map(f64::from), b.map(|v| f64::from(v) * 1.000_000_1));
            let (x, y) = (F64x16::from_array(k, a), F64x16::from_array(k, b));
            let m = Mask16(rng.below(1 << 16) as u16);
            let results: [Binary64<B>; 10] = [
                ("add", x + y, |a, b| a + b),
                ("sub", x - y, |a, b| a - b),
                ("mul", x * y, |a, b| a * b),
                ("div", x / y, |a, b| a / b),
                ("min", x.min(y), |a, b| if a < b { a } else { b }),
                ("sqrt", x.sqrt(), |a, _| a.sqrt()),
                ("abs", x.abs(), |a, _| a.abs()),
                ("neg", -x, |a, _| -a),
                (
                    "clamp",
                    x.clamp(F64x16::splat(k, -1.0), F64x16::splat(k, 1.0)),
                    |a, _| a.clamp(-1.0, 1.0),
                ),
                ("to_f32", x, |a, _| a),
            ];
            for (name, got, f) in results {
                for (i, g) in got.to_array().into_iter().enumerate() {
                    assert!(same64(g, f(a[i], b[i])), "{name}({}, {})", a[i], b[i]);
                }
            }
            let narrow = x.to_f32().to_array();
            let selected = F64x16::select(m, x, y).to_array();
            let compares = [x.le(y), x.gt(y), x.ge(y)];
            for i in 0..LANES {
                assert!(same(narrow[i], a[i] as f32));
                assert!(same64(selected[i], if m.test(i) { a[i] } else { b[i] }));
                let expected = [a[i] <= b[i], a[i] > b[i], a[i] >= b[i]];
                for (c, e) in compares.iter().zip(expected) {
                    assert_eq!(c.test(i), e, "{} against {}", a[i], b[i]);
                }
            }
        }
    }
    crate::simd::each_backend!(on);
}

/// A scalar integer operation of two lanes and a shift.
type Ternary = fn(u32, u32, u32) -> u32;

#[test]
fn integer_lanes_match_wrapping_scalar_operations() {
    fn on<B: Lanes>(k: B) {
        let mut rng = Rng::new(3);
        for _ in 0..2000 {
            let a: [u32; LANES] = std::array::from_fn(|_| rng.below(1 << 32) as u32);
            let b: [u32; LANES] = std::array::from_fn(|_| rng.below(1 << 32) as u32);
            let (x, y) = (U32x16::from_array(k, a), U32x16::from_array(k, b));
            let n = rng.below(33) as u32;
            let results: [(U32x16<B>, Ternary); 7] = [
                (x + y, |a, b, _| a.wrapping_add(b)),
                (x - y, |a, b, _| a.wrapping_sub(b)),
                (x * y, |a, b, _| a.wrapping_mul(b)),
                (x & y, |a, b, _| a & b),
                (x | y, |a, b, _| a | b),
                (x ^ y, |a, b, _| a ^ b),
                (x >> n, |a, _, n| a.checked_shr(n).unwrap_or(0)),
            ];
            for (got, f) in results {
                for (i, g) in got.to_array().into_iter().enumerate() {
                    assert_eq!(g, f(a[i], b[i], n));
                }
            }
            let shifted = (x << n).to_array();
            for i in 0..LANES {
                assert_eq!(shifted[i], a[i].checked_shl(n).unwrap_or(0));
                assert_eq!(x.lt(y).test(i), a[i] < b[i]);
                assert_eq!(x.ge(y).test(i), a[i] >= b[i]);
                assert!(x.eq(x).test(i));
            }
            // 64-bit lanes.
            let c: [u64; LANES] = std::array::from_fn(|i| u64::from(a[i]) << 32 | u64::from(b[i]));
            let d: [u64; LANES] =
                std::array::from_fn(|i| u64::from(b[i]).wrapping_mul(0x9E37_79B9));
            let (cx, dx) = (U64x16::from_array(k, c), U64x16::from_array(k, d));
            let (sum, product, xor, shifted) = (cx + dx, cx * dx, cx ^ dx, cx >> (n + 10));
            let (low, widened) = (cx.low_u32().to_array(), U64x16::from_u32(x).to_array());
            for i in 0..LANES {
                assert_eq!(sum.to_array()[i], c[i].wrapping_add(d[i]));
                assert_eq!(product.to_array()[i], c[i].wrapping_mul(d[i]));
                assert_eq!(xor.to_array()[i], c[i] ^ d[i]);
                assert_eq!(shifted.to_array()[i], c[i] >> (n + 10));
                assert_eq!(low[i], c[i] as u32);
                assert_eq!(widened[i], u64::from(a[i]));
            }
        }
    }
    crate::simd::each_backend!(on);
}

#[test]
fn masks_and_gathers() {
    fn on<B: Lanes>(k: B) {
        let mut rng = Rng::new(4);
        let table: Vec<f32> = (0..100).map(|i| i as f32 * 0.5).collect();
        let words: Vec<u32> = (0..100).map(|i| i * 7).collect();
        for n in 0..=LANES {
            assert_eq!(Mask16::first(n).count(), n as u32);
            assert_eq!(
                Mask16::first(n).lanes().collect::<Vec<_>>(),
                (0..n).collect::<Vec<_>>()
            );
        }
        for _ in 0..500 {
            let m = Mask16(rng.below(1 << 16) as u16);
            let index: [u32; LANES] = std::array::from_fn(|i| {
                if m.test(i) {
                    rng.below(100) as u32
                } else {
                    u32::MAX - rng.below(10) as u32
                }
            });
            let ix = U32x16::from_array(k, index);
            let got = F32x16::gather(&table, ix, m, F32x16::splat(k, -1.0)).to_array();
            let got_u = U32x16::gather(&words, ix, m, U32x16::splat(k, 9)).to_array();
            let longs: Vec<u64> = words.iter().map(|&w| u64::from(w) << 33 | 1).collect();
            let got_64 = U64x16::gather(&longs, ix, m, U64x16::splat(k, 3)).to_array();
            for i in 0..LANES {
                if m.test(i) {
                    assert_eq!(got[i], table[index[i] as usize]);
                    assert_eq!(got_u[i], words[index[i] as usize]);
                    assert_eq!(got_64[i], longs[index[i] as usize]);
                } else {
                    assert_eq!((got[i], got_u[i], got_64[i]), (-1.0, 9, 3));
                }
            }
            assert_eq!(m.lanes().count() as u32, m.count());
            assert_eq!((m & !m, m | !m), (Mask16::NONE, Mask16::ALL));
        }
    }
    crate::simd::each_backend!(on);
}

#[test]
#[should_panic(expected = "gather index out of bounds")]
fn gathers_check_their_indices() {
    // The check is the lane types', before any backend reads.
    let k = Portable;
    let table = [1.0f32; 4];
    let index = U32x16::from_array(k, std::array::from_fn(|i| i as u32));
    F32x16::gather(&table, index, Mask16::first(5), F32x16::splat(k, 0.0));
}

#[test]
fn vectors_match_glam() {
    fn on<B: Lanes>(k: B) {
        let mut rng = Rng::new(5);
        for _ in 0..1000 {
            let lanes = |rng: &mut Rng| -> [Vec3; LANES] {
                std::array::from_fn(|_| {
                    let v = rng.dvec3(-10.0, 10.0).as_vec3();
                    if rng.below(8) == 0 { Vec3::ZERO } else { v }
                })
            };
            let (a, b) = (lanes(&mut rng), lanes(&mut rng));
            let (x, y) = (Vec3x16::from_lanes(k, &a), Vec3x16::from_lanes(k, &b));
            let s = F32x16::from_array(k, values(&mut rng));
            let vectors = [
                (x + y).to_lanes(),
                (x - y).to_lanes(),
                (x * y).to_lanes(),
                (x * s).to_lanes(),
                x.div(s).to_lanes(),
                x.normalize(k).to_lanes(),
                (-x).to_lanes(),
            ];
            let (dot, len, max) = (x.dot(y), x.length(), x.max_element());
            let zero = x.is_zero(k);
            for i in 0..LANES {
                let si = s.lane(i);
                let expected = [
                    a[i] + b[i],
                    a[i] - b[i],
                    a[i] * b[i],
                    a[i] * si,
                    a[i] / si,
                    a[i] * (1.0 / a[i].length()),
                    -a[i],
                ];
                for (got, e) in vectors.iter().zip(expected) {
                    for c in 0..3 {
                        assert!(same(got[i][c], e[c]), "{:?} against {e:?}", got[i]);
                    }
                }
                assert!(same(dot.lane(i), a[i].dot(b[i])));
                assert!(same(len.lane(i), a[i].length()));
                assert!(same(max.lane(i), a[i].max_element()));
                assert_eq!(zero.test(i), a[i] == Vec3::ZERO);
            }
        }
    }
    crate::simd::each_backend!(on);
}

#[test]
fn permutes_minima_and_f64_copysign_match_scalar_operations() {
    fn on<B: Lanes>(k: B) {
        let mut rng = Rng::new(6);
        for _ in 0..2000 {
            let (a, b) = (values(&mut rng), values(&mut rng));
            let x = F32x16::from_array(k, a);
            let index: [u32; LANES] = std::array::from_fn(|_| rng.u64() as u32);
            let permuted = x.permute(U32x16::from_array(k, index)).to_array();
            for i in 0..LANES {
                assert!(same(permuted[i], a[index[i] as usize % LANES]));
            }
            let m = Mask16(rng.below(1 << 16) as u16);
            let finite = a.map(|v| if v.is_nan() { 0.5 } else { v });
            let smallest = m
                .lanes()
                .map(|i| finite[i])
                .fold(f32::INFINITY, |s, v| if v < s { v } else { s });
            // A ±0 tie may yield either zero: compare values, not bits.
            assert_eq!(F32x16::from_array(k, finite).reduce_min(m), smallest);
            let (a, b) = (a.map(f64::from), b.map(f64::from));
            let signed = F64x16::from_array(k, a).copysign(F64x16::from_array(k, b));
            for (i, got) in signed.to_array().into_iter().enumerate() {
                assert!(same64(got, a[i].copysign(b[i])), "{} {}", a[i], b[i]);
            }
        }
    }
    crate::simd::each_backend!(on);
}

#[test]
fn expanding_loads_fill_the_masked_lanes_in_order() {
    fn on<B: Lanes>(k: B) {
        let mut rng = Rng::new(6);
        let src: Vec<f32> = (0..16).map(|i| i as f32 + 0.5).collect();
        let words: Vec<u64> = (0..16).map(|i| (i as u64) << 40 | 7).collect();
        for _ in 0..300 {
            let m = Mask16(rng.below(1 << 16) as u16);
            let start = rng.below(16 - m.count() as usize + 1);
            let got = F32x16::splat(k, -1.0)
                .expand_from(m, &src[start..])
                .to_array();
            let got_u = U64x16::splat(k, 9)
                .expand_from(m, &words[start..])
                .to_array();
            let mut next = start;
            for i in 0..LANES {
                if m.test(i) {
                    assert_eq!((got[i], got_u[i]), (src[next], words[next]));
                    next += 1;
                } else {
                    assert_eq!((got[i], got_u[i]), (-1.0, 9));
                }
            }
        }
    }
    crate::simd::each_backend!(on);
}
