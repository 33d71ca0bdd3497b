//! A bounding volume hierarchy over beam volumes clipped to the scene bounds, so that a fragment visits the beams whose boxes hold it instead of all of them (Duvenhage et al. 2010, sections 4.3 and 5.2: future work, "a beam hierarchy similar to the cone hierarchy used by Chuang and Cheng [1995]").
//!
//! Written here rather than taken from `obvhs`: the query is a point in
//! boxes (not a ray), the tree is built once per beam set and holds a few
//! thousand boxes, and a median split on the longest axis of the centroids
//! keeps it balanced, so a visit is `O(log n)` plus the boxes that really
//! overlap the point.

use glam::Vec3;
use lustre_geometry::Aabb;

/// Boxes per leaf at most.
const LEAF_SIZE: usize = 4;

#[derive(Debug, Clone, Copy, PartialEq)]
struct Node {
    bounds: Aabb,
    /// Leaf: first item in `items`; inner: index of the left child (the right one follows the left subtree).
    first: u32,
    /// Leaf: number of items; inner: 0.
    count: u32,
    /// Inner: index of the right child.
    right: u32,
}

/// A node of [`BeamHierarchy::nodes`]: a leaf holds `count > 0` items from `link` on in [`BeamHierarchy::items`]; an inner node (`count == 0`) has its left child right after it and its right child at `link`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HierarchyNode {
    /// The union of the boxes below.
    pub bounds: Aabb,
    /// Leaf: first item; inner: index of the right child.
    pub link: u32,
    /// Items of a leaf; 0 for an inner node.
    pub count: u32,
}

/// A bounding volume hierarchy over item boxes, queried with points.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct BeamHierarchy {
    nodes: Vec<Node>,
    items: Vec<u32>,
}

impl BeamHierarchy {
    /// The hierarchy over `boxes` (index = item); empty boxes are left out.
    pub fn build(boxes: &[Aabb]) -> Self {
        let mut items: Vec<u32> = (0..boxes.len() as u32)
            .filter(|&i| !boxes[i as usize].is_empty())
            .collect();
        let mut nodes = Vec::with_capacity(2 * items.len() / LEAF_SIZE + 1);
        if !items.is_empty() {
            let n = items.len();
            build_node(boxes, &mut items, 0, n, &mut nodes);
        }
        Self { nodes, items }
    }

    /// Number of items in the tree.
    pub fn len(&self) -> usize {
        self.items.len()
    }

    /// Whether the tree holds no item.
    pub fn is_empty(&self) -> bool {
        self.items.is_empty()
    }

    /// The nodes in depth-first order (a node's left child follows it), for an upload to the GPU.
    pub fn nodes(&self) -> Vec<HierarchyNode> {
        self.nodes
            .iter()
            .map(|n| HierarchyNode {
                bounds: n.bounds,
                link: if n.count > 0 { n.first } else { n.right },
                count: n.count,
            })
            .collect()
    }

    /// The items, leaf by leaf: a leaf's items are `items()[link..link + count]`.
    pub fn items(&self) -> &[u32] {
        &self.items
    }

    /// Calls `visit` with every item whose box holds `p` (boundaries included), in no particular order; returns how many nodes were visited.
    pub fn for_each_containing(&self, p: Vec3, mut visit: impl FnMut(u32)) -> usize {
        let mut visited = 0;
        if self.nodes.is_empty() {
            return 0;
        }
        let mut stack = vec![0u32];
        while let Some(i) = stack.pop() {
            let node = &self.nodes[i as usize];
            visited += 1;
            if !holds(&node.bounds, p) {
                continue;
            }
            if node.count > 0 {
                let (a, b) = (node.first as usize, (node.first + node.count) as usize);
                for &item in &self.items[a..b] {
                    visit(item);
                }
            } else {
                stack.push(node.right);
                stack.push(node.first);
            }
        }
        visited
    }
}

fn holds(b: &Aabb, p: Vec3) -> bool {
    p.cmpge(b.min).all() && p.cmple(b.max).all()
}

/// Builds the subtree over `items[start..end]`, returns its node index.
fn build_node(
    boxes: &[Aabb],
    items: &mut [u32],
    start: usize,
    end: usize,
    nodes: &mut Vec<Node>,
) -> u32 {
    let bounds = items[start..end]
        .iter()
        .fold(Aabb::EMPTY, |acc, &i| acc.union(boxes[i as usize]));
    let index = nodes.len() as u32;
    nodes.push(Node {
        bounds,
        first: start as u32,
        count: (end - start) as u32,
        right: 0,
    });
    if end - start <= LEAF_SIZE {
        return index;
    }
    let centroids = items[start..end]
        .iter()
        .fold(Aabb::EMPTY, |acc, &i| acc.grow(boxes[i as usize].center()));
    let extent = centroids.extent();
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let mid = (start + end) / 2;
    items[start..end].select_nth_unstable_by(mid - start, |&a, &b| {
        let (ca, cb) = (
            boxes[a as usize].center()[axis],
            boxes[b as usize].center()[axis],
        );
        ca.total_cmp(&cb)
    });
    let left = build_node(boxes, items, start, mid, nodes);
    let right = build_node(boxes, items, mid, end, nodes);
    nodes[index as usize] = Node {
        bounds,
        first: left,
        count: 0,
        right,
    };
    index
}
