//! Every lane of every sixteen-lane light function against the scalar
//! function, bit for bit, on random scenes ([`random`]), from reference
//! points on the emitters, in their planes and on either side, on every
//! backend the CPU has (the portable one always). The shipped scenes' lights
//! are checked from outside the crate, where their loader is
//! (`tests/wide.rs`: their images per backend).

mod random;

use glam::{Vec2, Vec3};

use super::super::{Background, LightPoint, LightSample, LightTable};
use crate::simd::{F32x16, LANES, Lanes, Mask16, U32x16, Vec3x16};
use epsm_testkit::Rng;
use random::{emitter_point, lanes, random_table, reference, uniform};

/// Equal bit patterns, or both NaN.
fn same(a: f32, b: f32) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

/// [`same`] for every component.
fn same3(a: Vec3, b: Vec3) -> bool {
    (0..3).all(|c| same(a[c], b[c]))
}

/// Sixteen lanes of [`LightTable::sample`]'s inputs.
struct Inputs {
    /// Reference points.
    p: [Vec3; LANES],
    /// Light selection numbers.
    u_select: [f32; LANES],
    /// Numbers for the point on the light.
    u: [Vec2; LANES],
}

impl Inputs {
    /// The inputs as `sample16` takes them.
    fn lanes<B: Lanes>(&self, k: B) -> (Vec3x16<B>, F32x16<B>, [F32x16<B>; 2]) {
        let u = [self.u.map(|u| u.x), self.u.map(|u| u.y)];
        (
            Vec3x16::from_lanes(k, &self.p),
            F32x16::from_array(k, self.u_select),
            [F32x16::from_array(k, u[0]), F32x16::from_array(k, u[1])],
        )
    }
}

/// Whether a wide lane's sample is bit for bit the scalar `scalar`.
fn same_sample(wide: &SampleLane, scalar: &LightSample) -> bool {
    same3(wide.wo, scalar.wo)
        && same(wide.dist, scalar.dist)
        && same3(wide.position, scalar.position)
        && same3(wide.normal, scalar.normal)
        && same3(wide.radiance, scalar.radiance)
        && same(wide.pdf, scalar.pdf)
        && wide.delta == scalar.delta
}

/// One found lane of a [`super::LightSamples16`].
#[derive(Debug)]
struct SampleLane {
    wo: Vec3,
    dist: f32,
    position: Vec3,
    normal: Vec3,
    radiance: Vec3,
    pdf: f32,
    delta: bool,
}

/// Compares `sample16`, `pdf_area16`, `pdf_background16` and `eval16` with
/// the scalar functions on `rounds` random batches of `table`; returns how
/// many active lanes found an area light, a point light and the background.
fn check_table<B: Lanes>(k: B, table: &LightTable, rng: &mut Rng, rounds: usize) -> [usize; 3] {
    let mut found = [0; 3];
    for _ in 0..rounds {
        let inputs = Inputs {
            p: std::array::from_fn(|_| reference(table, rng)),
            u_select: std::array::from_fn(|_| uniform(rng)),
            u: std::array::from_fn(|_| Vec2::new(uniform(rng), uniform(rng))),
        };
        let Inputs { p, u_select, u } = inputs;
        let active = lanes(rng);
        let (p16, u_select16, u16) = inputs.lanes(k);
        let wide = table.sample16(k, p16, u_select16, u16, active);
        for i in 0..LANES {
            let scalar = table
                .sample(p[i], u_select[i], u[i])
                .filter(|_| active.test(i));
            assert_eq!(
                wide.found.test(i),
                scalar.is_some(),
                "lane {i}: {p:?} {u_select:?} {u:?}"
            );
            let Some(scalar) = scalar else { continue };
            found[match scalar.source {
                LightPoint::Area { .. } => 0,
                LightPoint::Point { .. } => 1,
                LightPoint::Background => 2,
            }] += 1;
            let lane = SampleLane {
                wo: wide.wo.lane(i),
                dist: wide.dist.lane(i),
                position: wide.position.lane(i),
                normal: wide.normal.lane(i),
                radiance: wide.radiance.lane(i),
                pdf: wide.pdf.lane(i),
                delta: wide.delta.test(i),
            };
            assert!(
                same_sample(&lane, &scalar),
                "lane {i}: {lane:?} against {scalar:?}"
            );
        }
        check_pdfs(k, table, rng, &p, active);
    }
    found
}

/// `pdf_area16` on points of emitter triangles (of emitters, non-emitters
/// and objects out of range) with normals of either orientation or none,
/// and `pdf_background16` and `eval16` on directions, from `p`.
fn check_pdfs<B: Lanes>(
    k: B,
    table: &LightTable,
    rng: &mut Rng,
    p: &[Vec3; LANES],
    active: Mask16,
) {
    let objects = table.emitter_of_object.len();
    let (mut object, mut triangle) = ([0u32; LANES], [0u32; LANES]);
    let (mut y, mut n) = ([Vec3::ZERO; LANES], [Vec3::ZERO; LANES]);
    for i in 0..LANES {
        object[i] = rng.below(objects + 2) as u32;
        y[i] = rng.dvec3(-4.0, 4.0).as_vec3();
        n[i] = rng.sphere();
        triangle[i] = rng.below(60) as u32;
        let Some(&Some(e)) = table.emitter_of_object.get(object[i] as usize) else {
            continue;
        };
        let t = rng.below(table.area[e as usize].triangles().len());
        let (a, b) = (rng.f32(), rng.f32());
        triangle[i] = t as u32;
        y[i] = emitter_point(table, e as usize, t, [a, b * (1.0 - a), 0.0]);
        let normal = table.area[e as usize].normal(t as u32);
        n[i] = [normal, -normal, n[i], Vec3::ZERO][rng.below(4)];
    }
    let wide = table.pdf_area16(
        k,
        U32x16::from_array(k, object),
        U32x16::from_array(k, triangle),
        Vec3x16::from_lanes(k, p),
        Vec3x16::from_lanes(k, &y),
        Vec3x16::from_lanes(k, &n),
        active,
    );
    let dir: [Vec3; LANES] = std::array::from_fn(|_| match rng.below(8) {
        0 => [Vec3::Y, -Vec3::Y, Vec3::Z, Vec3::ZERO][rng.below(4)],
        _ => rng.sphere(),
    });
    let dirs = Vec3x16::from_lanes(k, &dir);
    let (pdf, radiance) = (
        table.pdf_background16(k, dirs, active),
        table.background.eval16(k, dirs, active),
    );
    for i in active.lanes() {
        let scalar = table.pdf_area(object[i], triangle[i], p[i], y[i], n[i]);
        assert!(
            same(wide.lane(i), scalar),
            "pdf_area lane {i}: {} against {scalar}",
            wide.lane(i)
        );
        assert!(
            same(pdf.lane(i), table.pdf_background(dir[i])),
            "{:?}",
            dir[i]
        );
        assert!(
            same3(radiance.lane(i), table.background.eval(dir[i])),
            "{:?}",
            dir[i]
        );
    }
}

#[test]
fn random_scenes_match_the_scalar_functions_lane_by_lane() {
    fn on<B: Lanes>(k: B) {
        let mut rng = Rng::new(31);
        // Found lanes: area, point, constant background, environment map.
        let (mut found, mut small, mut large) = ([0; 4], 0, 0);
        for _ in 0..300 {
            let table = random_table(&mut rng);
            match table.selection.as_ref().map(|s| s.small_table().is_some()) {
                Some(true) => small += 1,
                Some(false) => large += 1,
                None => {}
            }
            let [area, point, background] = check_table(k, &table, &mut rng, 20);
            let map = usize::from(matches!(table.background, Background::EnvMap(_)));
            found[0] += area;
            found[1] += point;
            found[2 + map] += background;
        }
        assert!(
            small > 20 && large > 10,
            "{small} small and {large} large selection tables"
        );
        assert!(
            found.iter().all(|&n| n > 500),
            "area, point, constant, map: {found:?}"
        );
    }
    crate::simd::each_backend!(on);
}
