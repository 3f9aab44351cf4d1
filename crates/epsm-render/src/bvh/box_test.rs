//! How a ray is tested against a node's child boxes and its leaves' triangle
//! packets on this CPU: the [`BoxTest`] trait, its bodies with 128-bit
//! vectors ([`Portable`], every CPU) and 256-bit AVX vectors ([`Avx`], chosen
//! at run time; same masks and hits), the CPU level of the tracer's own code
//! ([`Avx2`]), and [`SpheresFirst`], which moves the listed exact spheres'
//! test ahead of the static BVH's walk.
//!
//! No parameters.

use super::node::{BoxHits, ChildBoxes, TraceRay};
use super::packet::{PacketHit, TrianglePacket};

/// How a node's eight child boxes, and the triangle packets of its leaves,
/// are tested against a ray, and where a trace tests a scene's listed exact
/// spheres.
pub(crate) trait BoxTest: Copy {
    /// The children whose boxes the ray enters within its `t` range and
    /// their entry distances (absent children count as entered: the caller
    /// masks them).
    fn hits(self, boxes: &ChildBoxes, ray: &TraceRay) -> BoxHits;

    /// The closest hit of `ray` within its `t` range among the lanes of
    /// `packet` in `lanes` (bit `i` for lane `i`), in the order of
    /// [`TrianglePacket::intersect_4x2`].
    fn packet_hit(self, packet: &TrianglePacket, ray: &TraceRay, lanes: u32) -> Option<PacketHit>;

    /// Whether a trace tests the listed exact spheres inline before the
    /// static BVH's walk ([`SpheresFirst`]) rather than out of line after
    /// it. Both find the same hit; the choice is the compiled code's.
    #[inline(always)]
    fn spheres_first(self) -> bool {
        false
    }
}

/// The tests of `B`, with a scene's listed exact spheres tested inline
/// before the static BVH's walk, their result kept aside until the walk
/// ends (a sphere's `f64` solve then overlaps the walk instead of following
/// its last branch). The tile loop of a scene that lists spheres is
/// compiled with it; that of a scene without keeps no state of theirs live
/// across the walk (inlined there, the test cost scenes without spheres
/// 1.5 % more instructions).
#[derive(Clone, Copy, Debug)]
pub(crate) struct SpheresFirst<B>(pub B);

impl<B: BoxTest> BoxTest for SpheresFirst<B> {
    #[inline(always)]
    fn hits(self, boxes: &ChildBoxes, ray: &TraceRay) -> BoxHits {
        self.0.hits(boxes, ray)
    }

    #[inline(always)]
    fn packet_hit(self, packet: &TrianglePacket, ray: &TraceRay, lanes: u32) -> Option<PacketHit> {
        self.0.packet_hit(packet, ray, lanes)
    }

    #[inline(always)]
    fn spheres_first(self) -> bool {
        true
    }
}

/// Box and packet tests with 128-bit vectors, on every CPU.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Portable;

impl BoxTest for Portable {
    #[inline(always)]
    fn hits(self, boxes: &ChildBoxes, ray: &TraceRay) -> BoxHits {
        boxes.hits_4x2(ray)
    }

    #[inline(always)]
    fn packet_hit(self, packet: &TrianglePacket, ray: &TraceRay, lanes: u32) -> Option<PacketHit> {
        packet.intersect_4x2(ray, lanes)
    }
}

/// Box and packet tests with 256-bit AVX vectors; a value exists only on a
/// CPU with AVX (see [`Avx::detect`]). Same masks and hits as [`Portable`].
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx(());

#[cfg(target_arch = "x86_64")]
impl Avx {
    /// The token, when the CPU has AVX.
    #[inline(always)]
    pub fn detect() -> Option<Self> {
        std::arch::is_x86_feature_detected!("avx").then_some(Self(()))
    }

    /// The token on a CPU with AVX-512 (which has AVX).
    #[inline(always)]
    pub fn from_avx512(_: crate::simd::Avx512) -> Self {
        Self(())
    }
}

/// The tracer's CPU level: AVX2 and the bit-manipulation extensions every
/// AVX2 CPU has (BMI1, BMI2, LZCNT, POPCNT), with [`Avx`] box tests. A value
/// exists only on a CPU with all of them (see [`Avx2::detect`]), so code
/// compiled with `#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]`
/// may be called while one is held. The tile loop and
/// [`Accel::closest_hit`](super::Accel::closest_hit) both walk with this
/// build where the CPU has it, and with [`Portable`] tests elsewhere.
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx2(Avx);

#[cfg(target_arch = "x86_64")]
impl Avx2 {
    /// The token, when the CPU has AVX, AVX2, BMI1, BMI2, LZCNT and POPCNT.
    #[inline(always)]
    pub fn detect() -> Option<Self> {
        let avx = Avx::detect()?;
        (std::arch::is_x86_feature_detected!("avx2")
            && std::arch::is_x86_feature_detected!("bmi1")
            && std::arch::is_x86_feature_detected!("bmi2")
            && std::arch::is_x86_feature_detected!("lzcnt")
            && std::arch::is_x86_feature_detected!("popcnt"))
        .then_some(Self(avx))
    }

    /// Its AVX box and packet tests.
    #[inline(always)]
    pub fn boxes(self) -> Avx {
        self.0
    }
}

#[cfg(target_arch = "x86_64")]
impl BoxTest for Avx {
    #[inline(always)]
    #[allow(unsafe_code)]
    fn hits(self, boxes: &ChildBoxes, ray: &TraceRay) -> BoxHits {
        // SAFETY: an `Avx` is only made by `Avx::detect` after finding AVX
        // on this CPU, which is all `hits_8` requires.
        unsafe { boxes.hits_8(ray) }
    }

    #[inline(always)]
    #[allow(unsafe_code)]
    fn packet_hit(self, packet: &TrianglePacket, ray: &TraceRay, lanes: u32) -> Option<PacketHit> {
        // SAFETY: as `hits`: `intersect_8_outlined` requires only AVX.
        unsafe { packet.intersect_8_outlined(ray, lanes) }
    }
}
