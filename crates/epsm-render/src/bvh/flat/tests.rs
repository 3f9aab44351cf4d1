//! Flat BVH tests: the flat walk against obvhs's walk and brute force, packet
//! children and lanes, and the packet test against the scalar triangle test.

use super::*;
use crate::bvh::Portable;
use crate::bvh::test_support::push_soup_triangle;
use crate::bvh::triangle::{PackedTriangle, RayShear};
use crate::scene::Mesh;
use epsm_testkit::Rng;
use glam::Vec3A;
use obvhs::BvhBuildParams;
use obvhs::ray::RayHit;

/// A soup of `count` triangles in `[-1, 1]³`: a third thin slivers, a
/// few exactly degenerate (left out), some sharing edges.
fn soup(rng: &mut Rng, count: usize) -> Mesh {
    let mut mesh = Mesh::default();
    for i in 0..count {
        push_soup_triangle(rng, &mut mesh, i);
    }
    mesh
}

/// The obvhs build (`very_fast_build`) of a [`soup`] of `count`, and how
/// many triangles the soup has (degenerate ones included).
fn built_soup(rng: &mut Rng, count: usize) -> (SlotTriangles, usize) {
    let mesh = soup(rng, count);
    let triangles = (0..mesh.len() as u32).map(|tri| (tri, mesh.triangle(tri).map(Vec3A::from)));
    let built = SlotTriangles::build(triangles, BvhBuildParams::very_fast_build());
    (built.expect("triangles"), mesh.len())
}

fn random_ray(rng: &mut Rng, i: usize) -> TraceRay {
    let origin = Vec3A::from(rng.dvec3(-1.6, 1.6).as_vec3());
    let mut dir = Vec3A::from(rng.unit().as_vec3());
    if i.is_multiple_of(5) {
        dir[rng.below(3)] = 0.0;
    }
    let t_max = if i.is_multiple_of(3) {
        rng.range(0.0, 2.0) as f32
    } else {
        f32::INFINITY
    };
    TraceRay::new(origin, dir * rng.range(0.5, 2.0) as f32, 0.0, t_max)
}

/// The flat walk finds the closest hit of brute force over the same
/// triangles and of obvhs's own traversal of the CWBVH it was converted
/// from (same `t`; the same triangle and barycentrics unless two are hit
/// at exactly that `t`), and occlusion agrees with the closest hit, for
/// rays made with and without the shear.
#[test]
fn flat_walk_matches_obvhs_walk_and_brute_force() {
    let mut rng = Rng::new(5);
    let (built, soup_len) = built_soup(&mut rng, 4000);
    let flat = FlatBvh::new(&built);
    assert!(flat.len() < soup_len, "degenerate triangles left out");
    assert!(flat.stack_need() <= STACK, "{}", flat.stack_need());
    let (mut hits, mut compared) = (0, 0);
    for i in 0..20_000 {
        let ray = random_ray(&mut rng, i);
        let found = flat.trace::<false>(&mut ray.clone(), Portable);
        let scalar = |slot: usize| {
            let tri = &built.triangles[slot];
            tri.intersect(ray.origin, &ray.shear, ray.t_min, ray.t_max)
        };
        let brute = (0..built.triangles.len())
            .filter_map(|slot| Some((built.ids[slot], scalar(slot)?)))
            .min_by(|a, b| a.1.t.total_cmp(&b.1.t));
        assert_eq!(found.map(|h| h.t), brute.map(|b| b.1.t), "ray {i}: {ray:?}");
        // obvhs culls boxes nearer than 1e-4 and accepts only `t < t_max`.
        let mut obvhs_hit = RayHit::none();
        let obvhs_ray = obvhs::ray::Ray::new(ray.origin, ray.dir, ray.t_min, ray.t_max);
        let walked = built
            .bvh
            .ray_traverse(obvhs_ray, &mut obvhs_hit, |_, slot| {
                scalar(slot).map_or(f32::INFINITY, |h| h.t)
            });
        if let Some(f) = found
            && f.t > 1e-3
            && f.t < ray.t_max
        {
            assert!(walked, "ray {i}");
            assert_eq!(f.t, obvhs_hit.t, "ray {i}");
            let slot = obvhs_hit.primitive_id as usize;
            if built.ids[slot] == f.id {
                let h = scalar(slot).expect("hit");
                assert_eq!((f.b1, f.b2), (h.b1, h.b2), "ray {i}");
            }
            compared += 1;
        }
        let occluded = flat.trace::<true>(&mut ray.clone(), Portable);
        assert_eq!(occluded.is_some(), found.is_some(), "ray {i}");
        // Occlusion walks set the shear of rays made without it; a
        // closest-hit walk of such a ray finds nothing.
        let unsheared = TraceRay::without_shear(ray.origin, ray.dir, ray.t_min, ray.t_max);
        let occluded = flat.trace::<true>(&mut unsheared.clone(), Portable);
        assert_eq!(occluded.is_some(), found.is_some(), "ray {i}");
        assert_eq!(flat.trace::<false>(&mut unsheared.clone(), Portable), None);
        hits += usize::from(found.is_some());
    }
    assert!(
        hits > 4000 && compared > 3000,
        "{hits} hits, {compared} compared"
    );
}

/// A node's `packet_children` byte of each packet is the union of its
/// lanes' children, and zero past its packets.
#[test]
fn packet_children_match_packets() {
    let mut rng = Rng::new(4);
    let (built, _) = built_soup(&mut rng, 3000);
    let flat = FlatBvh::new(&built);
    let mut several = 0;
    for n in &flat.nodes {
        for p in 0..4 {
            let byte = n.packet_children >> (8 * p) & 0xff;
            let expected = if p < n.packet_count as usize {
                let packet = &flat.packets[n.first_packet as usize + p];
                (0..8)
                    .filter(|&c| packet.lanes_of(1 << c) != 0)
                    .fold(0, |m, c| m | 1 << c)
            } else {
                0
            };
            assert_eq!(byte, expected, "packet {p}");
        }
        several += usize::from(n.packet_count > 1);
    }
    assert!(several > 10, "{several}");
}

/// `lanes_of` finds the lanes of the children asked for.
#[test]
fn lanes_of_children() {
    let mut rng = Rng::new(3);
    let (built, _) = built_soup(&mut rng, 20);
    let ids: Vec<u32> = (0..LANES as u32).collect();
    for bits in [
        [1u8, 1, 2, 128, 4, 8, 8, 16],
        [4, 8, 8, 16, 64, 128, 1, 2],
        [64, 128, 1, 2, 32, 32, 32, 1],
    ] {
        let packet = TrianglePacket::new(&built.triangles[..LANES], &ids, &bits);
        for children in 0..256u32 {
            let expected = (0..LANES)
                .filter(|&l| u32::from(bits[l]) & children != 0)
                .fold(0, |m, l| m | 1 << l);
            assert_eq!(
                packet.lanes_of(children),
                expected,
                "{bits:?} {children:#b}"
            );
        }
    }
    let short = TrianglePacket::new(&built.triangles[..2], &[0, 1], &[1, 2]);
    assert_eq!(short.lanes_of(0xff), 0b11);
}

/// The reference of a packet's hit: the scalar test of each lane in
/// `lanes`, lanes 0–3 then 4–7, each half's closest hit (the lowest lane
/// among equal `t`) lowering `t_max` for the next.
fn scalar_packet_hit(
    triangles: &[PackedTriangle],
    origin: Vec3A,
    shear: &RayShear,
    lanes: u32,
) -> Option<(usize, f32, f32, f32)> {
    let (mut best, mut t_max) = (None, 10.0);
    for half in [0..4, 4..LANES] {
        let hit = half
            .filter(|&l| l < triangles.len() && lanes & (1 << l) != 0)
            .filter_map(|l| Some((l, triangles[l].intersect(origin, shear, 0.0, t_max)?)))
            .min_by(|a, b| a.1.t.total_cmp(&b.1.t));
        if let Some((l, h)) = hit {
            t_max = h.t;
            best = Some((l, h.t, h.b1, h.b2));
        }
    }
    best
}

/// Every lane of a packet hits exactly as the scalar test of its
/// triangle, through edges, vertices and the f64 fallback, with both
/// packet tests (AVX where the CPU has it), for packets of one to eight
/// triangles, some repeated in both halves (ties across halves), and
/// random lane masks.
#[test]
fn packet_lanes_match_scalar_test() {
    #[cfg(target_arch = "x86_64")]
    let avx = crate::bvh::Avx::detect();
    let mut rng = Rng::new(9);
    let (built, _) = built_soup(&mut rng, 600);
    let (mut hits, mut second_half_ties) = (0, 0);
    for (k, chunk) in built.triangles.chunks(5).enumerate() {
        // Packets of 1..=8 lanes; from 6 lanes on, lanes 5.. repeat
        // lanes 0.. (the same triangle in both halves).
        let len = 1 + k % LANES;
        let triangles: Vec<_> = (0..len).map(|l| chunk[l % 5 % chunk.len()]).collect();
        let ids: Vec<u32> = (0..len as u32).collect();
        let packet = TrianglePacket::new(&triangles, &ids, &[1; LANES][..len]);
        for i in 0..40 {
            // Rays aimed at a vertex, an edge point or inside.
            let target = triangles[i % len].vertices();
            let w = match i % 3 {
                0 => [1.0, 0.0, 0.0],
                1 => [0.5, 0.5, 0.0],
                _ => [0.2, 0.3, 0.5],
            };
            let aim = target[0] * w[0] + target[1] * w[1] + target[2] * w[2];
            let origin = Vec3A::from(rng.dvec3(-2.0, 2.0).as_vec3());
            let ray = TraceRay::new(origin, aim - origin, 0.0, 10.0);
            let lanes = if i % 4 == 0 {
                rng.below(256) as u32
            } else {
                0xff
            };
            let scalar = scalar_packet_hit(&triangles, origin, &ray.shear, lanes);
            let portable = packet.intersect_4x2(&ray, lanes);
            let found = portable.map(|h| (h.lane, h.t, h.b1, h.b2));
            assert_eq!(found, scalar, "packet {k} ray {i}");
            #[cfg(target_arch = "x86_64")]
            if avx.is_some() {
                // SAFETY: the CPU has AVX (`Avx::detect`).
                #[allow(unsafe_code)]
                let wide = unsafe { packet.intersect_8(&ray, lanes) };
                assert_eq!(wide, portable, "packet {k} ray {i}");
            }
            hits += usize::from(found.is_some());
            second_half_ties += usize::from(found.is_some_and(|h| h.0 >= 5));
        }
    }
    assert!(
        hits > 3000 && second_half_ties > 200,
        "{hits} {second_half_ties}"
    );
}
