//! The crossings of a disc set (section 1.2: "the rays intersecting a given disc"): per disc, the ascending indices of the segments crossing it, kept in one flat list with each disc's start rather than one allocation per disc.

use std::ops::Index;

/// Per disc, the ascending indices of the segments crossing it (section 1.2), in one flat list.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Crossings {
    /// Disc `i`'s segments are `ids[start[i]..start[i + 1]]`; one entry more than there are discs.
    start: Vec<usize>,
    /// Segment indices, disc by disc.
    ids: Vec<u32>,
}

impl Crossings {
    /// From each disc's start into `ids` (one entry more than there are discs, the last `ids.len()`) and the segment indices disc by disc.
    pub(crate) fn from_parts(start: Vec<usize>, ids: Vec<u32>) -> Self {
        debug_assert_eq!(start.last().copied().unwrap_or(0), ids.len());
        let start = if start.is_empty() { vec![0] } else { start };
        Self { start, ids }
    }

    /// From one list per disc.
    pub(crate) fn from_lists(lists: Vec<Vec<u32>>) -> Self {
        let mut start = Vec::with_capacity(lists.len() + 1);
        start.push(0);
        let mut ids = Vec::with_capacity(lists.iter().map(Vec::len).sum());
        for list in lists {
            ids.extend(list);
            start.push(ids.len());
        }
        Self { start, ids }
    }

    /// From `(disc, segment)` pairs over `discs` discs, in the order given (chunk by chunk): each disc's
    /// segments in the order its pairs come.
    pub(crate) fn from_pairs(discs: usize, pairs: &[Vec<(u32, u32)>]) -> Self {
        let mut start = vec![0usize; discs + 1];
        for &(i, _) in pairs.iter().flatten() {
            start[i as usize + 1] += 1;
        }
        for i in 0..discs {
            start[i + 1] += start[i];
        }
        let mut next = start.clone();
        let mut ids = vec![0u32; start[discs]];
        for &(i, j) in pairs.iter().flatten() {
            ids[next[i as usize]] = j;
            next[i as usize] += 1;
        }
        Self::from_parts(start, ids)
    }

    /// Sorts each disc's segments into ascending order.
    pub(crate) fn sort_each(&mut self) {
        for w in self.start.windows(2) {
            let list = &mut self.ids[w[0]..w[1]];
            if !list.is_sorted() {
                list.sort_unstable();
            }
        }
    }

    /// Number of discs.
    pub fn len(&self) -> usize {
        self.start.len() - 1
    }

    /// Whether there is no disc.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of (disc, segment) crossings over every disc.
    pub fn pairs(&self) -> usize {
        self.ids.len()
    }

    /// Disc `i`'s crossing segments, or `None` past the last disc.
    pub fn get(&self, i: usize) -> Option<&[u32]> {
        let (a, b) = (*self.start.get(i)?, *self.start.get(i + 1)?);
        Some(&self.ids[a..b])
    }

    /// Every disc's crossing segments, in disc order.
    pub fn iter(&self) -> impl ExactSizeIterator<Item = &[u32]> + '_ {
        self.start.windows(2).map(|w| &self.ids[w[0]..w[1]])
    }
}

impl Index<usize> for Crossings {
    type Output = [u32];

    /// Disc `i`'s crossing segments; panics past the last disc, as a slice does.
    fn index(&self, i: usize) -> &[u32] {
        &self.ids[self.start[i]..self.start[i + 1]]
    }
}
