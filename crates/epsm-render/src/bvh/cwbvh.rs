//! obvhs's CWBVH with exact child boxes: [`WideNode`]s, whose eight child
//! boxes are exact `f32` planes ([`ChildBoxes`]) instead of obvhs's 8-bit
//! quantised ones, walked at the top level (module `walk`); and the exact
//! child boxes of any CWBVH, from which the bottom levels' flat nodes are
//! built too (module `flat`).
//!
//! No parameters.

use obvhs::aabb::Aabb;
use obvhs::cwbvh::CwBvh;
use obvhs::cwbvh::node::{CwBvhNode, extract_byte64};

use super::box_test::BoxTest;
use super::node::{ChildBoxes, TraceRay};

/// A CWBVH node with its eight child boxes decompressed to exact `f32`
/// planes ([`ChildBoxes`]), so the slab test converts no bytes. Field names
/// follow obvhs's `CwBvhNode`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct WideNode {
    /// The child boxes.
    boxes: ChildBoxes,
    /// Index of the first inner child node.
    pub child_base_idx: u32,
    /// Index of the first leaf primitive slot.
    pub primitive_base_idx: u32,
    /// obvhs's per-child metadata (leaf primitive ranges, inner-child slots).
    child_meta: [u8; 8],
    /// Which children are inner nodes.
    pub imask: u8,
    /// Bit `c` set when child `c` exists.
    present: u8,
}

impl WideNode {
    /// `node` with exact child boxes `children` (ignored for empty slots).
    fn new(node: &CwBvhNode, children: &[Aabb; 8]) -> Self {
        let present = std::array::from_fn(|child| !node.is_child_empty(child));
        Self {
            boxes: ChildBoxes::new(children, present),
            child_base_idx: node.child_base_idx,
            primitive_base_idx: node.primitive_base_idx,
            child_meta: node.child_meta,
            imask: node.imask,
            present: (0..8)
                .filter(|&c| !node.is_child_empty(c))
                .fold(0, |m, c| m | 1 << c),
        }
    }

    /// The CWBVH hit mask of `ray` (octant code `oct_inv4`, see
    /// [`TraceRay::oct_inv4`]) against the children, box tests by `boxes`:
    /// bits 24..32 are inner children to visit (in traversal order),
    /// bits 0..24 the leaf primitives to test (Ylitie et al.'s encoding, as
    /// obvhs's `CwBvhNode::get_child_and_index_bits`).
    #[inline(always)]
    pub fn intersect(&self, ray: &TraceRay, oct_inv4: u32, boxes: impl BoxTest) -> u32 {
        let mut hit_children = boxes.hits(&self.boxes, ray).mask & u32::from(self.present);
        let meta8 = u64::from_le_bytes(self.child_meta);
        let oct_inv8 = u64::from(oct_inv4) * 0x1_0000_0001;
        let inner8 = ((meta8 & (meta8 << 1)) & 0x1010_1010_1010_1010) >> 4;
        let bit_index8 = (meta8 ^ (oct_inv8 & (inner8 * 0xff))) & 0x1f1f_1f1f_1f1f_1f1f;
        let child_bits8 = (meta8 >> 5) & 0x0707_0707_0707_0707;
        // One iteration per child hit (a loop over set bits mispredicts once,
        // a test per child up to eight times).
        let mut hit_mask = 0u32;
        while hit_children != 0 {
            let child = hit_children.trailing_zeros() as usize;
            hit_children &= hit_children - 1;
            hit_mask |= extract_byte64(child_bits8, child) << extract_byte64(bit_index8, child);
        }
        hit_mask
    }
}

/// A CWBVH of [`WideNode`]s.
#[derive(Clone, Debug, Default)]
pub(crate) struct WideBvh {
    /// The nodes, root first.
    pub nodes: Vec<WideNode>,
}

impl WideBvh {
    /// The nodes of `bvh` with exact child boxes (tighter than its 8-bit
    /// quantised ones), from the box of each leaf primitive slot (`leaf_box`).
    pub fn new(bvh: &CwBvh, leaf_box: impl Fn(u32) -> Aabb) -> Self {
        let nodes = bvh.nodes.iter().zip(exact_child_boxes(bvh, leaf_box));
        Self {
            nodes: nodes
                .map(|(node, children)| WideNode::new(node, &children))
                .collect(),
        }
    }

    /// Heap size in bytes.
    pub fn bytes(&self) -> usize {
        self.nodes.len() * size_of::<WideNode>()
    }
}

/// Per node of `bvh`, the exact boxes of its eight children (empty for
/// absent children), from the box of each leaf primitive slot (`leaf_box`).
pub(crate) fn exact_child_boxes(bvh: &CwBvh, leaf_box: impl Fn(u32) -> Aabb) -> Vec<[Aabb; 8]> {
    // Children come after their parent in obvhs's layout: go bottom-up.
    let mut node_box = vec![Aabb::empty(); bvh.nodes.len()];
    let mut child_boxes = vec![[Aabb::empty(); 8]; bvh.nodes.len()];
    for (i, node) in bvh.nodes.iter().enumerate().rev() {
        for child in (0..8).filter(|&c| !node.is_child_empty(c)) {
            let aabb = if node.is_leaf(child) {
                let (start, count) = node.child_primitives(child);
                (start..start + count).fold(Aabb::empty(), |b, s| b.union(&leaf_box(s)))
            } else {
                node_box[node.child_node_index(child) as usize]
            };
            child_boxes[i][child] = aabb;
            node_box[i] = node_box[i].union(&aabb);
        }
    }
    child_boxes
}
