//! KFTS (key-frame trajectory sampling): the DAG of valid transitions between the key frames
//! of a task, exact counts of its length-L paths, and uniform sampling of unique paths by
//! weighted backtracking.

use std::collections::HashSet;

use rand::Rng;
use rayon::prelude::*;

use crate::scene_graph::{
    DiffError, GraphIndex, SceneGraphTimeline, StateDiff, StateVocabulary, View, sentence_count_in,
    visible_diff, visible_diff_indexed,
};

/// Fewest and most sentences an action may have for its transition to be usable.
pub const SENTENCES_PER_ACTION: std::ops::RangeInclusive<usize> = 1..=5;

/// The valid transitions over the key frames of one task, as indices into `frames`
/// (numeric order). Edges only go forward in time (`i < j`).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct TransitionGraph {
    frames: Vec<String>,
    /// `successors[i]`: the `j > i` with `i → j` valid, ascending.
    successors: Vec<Vec<u32>>,
    /// `predecessors[j]`: the `i < j` with `i → j` valid, ascending.
    predecessors: Vec<Vec<u32>>,
}

/// Why a transition graph or a path table could not be built.
#[derive(Debug, thiserror::Error)]
pub enum KftsError {
    #[error(transparent)]
    Diff(#[from] DiffError),
    #[error("{file}: frames {from} -> {to}: {source}")]
    Name {
        file: String,
        from: String,
        to: String,
        #[source]
        source: crate::scene_graph::NameError,
    },
    #[error("an edge {from} -> {to} is not forward in time over {frames} key frames")]
    EdgeNotForward {
        from: usize,
        to: usize,
        frames: usize,
    },
    /// Cannot happen below 30,000 key frames, see [`PathTable::count`].
    #[error("the number of length-{length} paths over {frames} key frames exceeds 2^128")]
    CountOverflow { length: usize, frames: usize },
    #[error("path length {0} is out of range: need at least 1")]
    ZeroLength(usize),
    #[error("more than {0} key frames: too many for 32-bit frame indices")]
    TooManyFrames(usize),
}

impl TransitionGraph {
    /// Builds a graph from explicit edges `(i, j)` with `i < j < frames.len()` (tests,
    /// synthetic trajectories).
    pub fn from_edges(
        frames: Vec<String>,
        edges: impl IntoIterator<Item = (usize, usize)>,
    ) -> Result<TransitionGraph, KftsError> {
        let n = frames.len();
        if u32::try_from(n).is_err() {
            return Err(KftsError::TooManyFrames(u32::MAX as usize));
        }
        let mut successors = vec![Vec::new(); n];
        let mut predecessors = vec![Vec::new(); n];
        for (i, j) in edges {
            if i >= j || j >= n {
                return Err(KftsError::EdgeNotForward {
                    from: i,
                    to: j,
                    frames: n,
                });
            }
            successors[i].push(j as u32);
            predecessors[j].push(i as u32);
        }
        for list in successors.iter_mut().chain(predecessors.iter_mut()) {
            list.sort_unstable();
            list.dedup();
        }
        Ok(TransitionGraph {
            frames,
            successors,
            predecessors,
        })
    }

    /// ENACT's `_build_valid_transitions_graph` over `key_frames` (sorted numerically here):
    /// `i → j` (i < j) is valid when the visible diff is non-empty, has a meaningful change
    /// and renders as 1 to 5 sentences. Diffs come from the raw (unfiltered) graphs.
    pub fn build(
        timeline: &SceneGraphTimeline,
        key_frames: &[String],
    ) -> Result<TransitionGraph, KftsError> {
        Self::build_in(timeline, key_frames, StateVocabulary::Enact)
    }

    /// [`TransitionGraph::build`] with the changes and sentences of `vocabulary` (a contact
    /// run counts and describes contact changes too).
    pub fn build_in(
        timeline: &SceneGraphTimeline,
        key_frames: &[String],
        vocabulary: StateVocabulary,
    ) -> Result<TransitionGraph, KftsError> {
        let mut frames = key_frames.to_vec();
        frames.sort_by_key(|f| f.parse::<u64>().unwrap_or(u64::MAX));
        let n = frames.len();
        // Each key frame is in n - 1 tests: its graph is indexed once for all of them.
        let graphs = frames
            .iter()
            .map(|f| timeline.scene_graph(f))
            .collect::<Result<Vec<_>, _>>()
            .map_err(DiffError::from)?;
        let indexes: Vec<GraphIndex<'_>> = graphs.par_iter().map(|g| GraphIndex::new(g)).collect();
        let rows: Vec<Vec<(usize, usize)>> = (0..n)
            .into_par_iter()
            .map(|i| {
                let mut row = Vec::new();
                for j in i + 1..n {
                    let diff = visible_diff_indexed(
                        timeline,
                        &frames[i],
                        &frames[j],
                        &indexes[i],
                        &indexes[j],
                        View::Visible,
                    )?;
                    if is_valid_diff(timeline, &frames[i], &frames[j], &diff, vocabulary)? {
                        row.push((i, j));
                    }
                }
                Ok(row)
            })
            .collect::<Result<_, KftsError>>()?;
        Self::from_edges(frames, rows.into_iter().flatten())
    }

    pub fn frames(&self) -> &[String] {
        &self.frames
    }

    pub fn successors(&self, i: usize) -> &[u32] {
        &self.successors[i]
    }

    pub fn predecessors(&self, j: usize) -> &[u32] {
        &self.predecessors[j]
    }

    pub fn edge_count(&self) -> usize {
        self.successors.iter().map(Vec::len).sum()
    }
}

/// One edge test of the KFTS graph (ENACT's `_is_valid_transition`).
pub fn is_valid_transition(
    timeline: &SceneGraphTimeline,
    from: &str,
    to: &str,
) -> Result<bool, KftsError> {
    let diff = visible_diff(timeline, from, to, View::Visible)?;
    is_valid_diff(timeline, from, to, &diff, StateVocabulary::Enact)
}

/// The test of [`is_valid_transition`] on the pair's visible diff.
fn is_valid_diff(
    timeline: &SceneGraphTimeline,
    from: &str,
    to: &str,
    diff: &StateDiff,
    vocabulary: StateVocabulary,
) -> Result<bool, KftsError> {
    if diff.is_empty() || !vocabulary.is_meaningful(diff) {
        return Ok(false);
    }
    let sentences = sentence_count_in(diff, vocabulary).map_err(|source| KftsError::Name {
        file: timeline.source().display().to_string(),
        from: from.to_string(),
        to: to.to_string(),
        source,
    })?;
    Ok(SENTENCES_PER_ACTION.contains(&sentences))
}

/// Path counts of one length over a [`TransitionGraph`], with what sampling needs.
#[derive(Debug, Clone)]
pub struct PathTable {
    length: usize,
    /// `dp[k][i]`: paths of k + 1 frames ending at frame i.
    dp: Vec<Vec<u128>>,
    /// `predecessor_prefix[k][i][m]`: Σ dp[k-1][p] over the first m + 1 predecessors p of i
    /// (k ≥ 1), so a weighted predecessor is found by binary search.
    predecessor_prefix: Vec<Vec<Vec<u128>>>,
    /// Prefix sums of `dp[length-1]` over the frames.
    end_prefix: Vec<u128>,
}

impl PathTable {
    /// ENACT's `_count_paths_with_dp` for paths of `length` frames, exactly.
    ///
    /// Why u128 suffices: a path is a strictly increasing sequence of frame indices, so there
    /// are at most C(n, k) paths of k frames over n key frames, and every DP cell and partial
    /// sum counts a subset of those. For k ≤ 10 and n ≤ 30,000, C(n, k) ≤ n^10 / 10! ≈
    /// 1.6·10^38 < 2^128 ≈ 3.4·10^38. (Key frames are more than `min_gap` = 200 frames apart by
    /// default, so 30,000 key frames would be a six-million-frame episode.) Beyond that the
    /// additions are checked and report [`KftsError::CountOverflow`] instead of wrapping.
    pub fn count(graph: &TransitionGraph, length: usize) -> Result<PathTable, KftsError> {
        if length == 0 {
            return Err(KftsError::ZeroLength(length));
        }
        let n = graph.frames.len();
        let overflow = || KftsError::CountOverflow { length, frames: n };
        let mut dp = vec![vec![1u128; n]];
        let mut predecessor_prefix = vec![Vec::new()];
        for k in 1..length {
            let prev = &dp[k - 1];
            let mut row = Vec::with_capacity(n);
            let mut prefixes = Vec::with_capacity(n);
            for preds in &graph.predecessors {
                let mut sum = 0u128;
                let mut prefix = Vec::with_capacity(preds.len());
                for &p in preds {
                    sum = sum.checked_add(prev[p as usize]).ok_or_else(overflow)?;
                    prefix.push(sum);
                }
                row.push(sum);
                prefixes.push(prefix);
            }
            dp.push(row);
            predecessor_prefix.push(prefixes);
        }
        let mut end_prefix = Vec::with_capacity(n);
        let mut sum = 0u128;
        for &c in &dp[length - 1] {
            sum = sum.checked_add(c).ok_or_else(overflow)?;
            end_prefix.push(sum);
        }
        Ok(PathTable {
            length,
            dp,
            predecessor_prefix,
            end_prefix,
        })
    }

    pub fn length(&self) -> usize {
        self.length
    }

    /// The number of valid paths of `length` frames (ENACT's `total_paths`).
    pub fn total(&self) -> u128 {
        self.end_prefix.last().copied().unwrap_or(0)
    }

    /// `dp[length-1]`: the number of paths ending at each frame.
    pub fn paths_ending_at(&self) -> &[u128] {
        &self.dp[self.length - 1]
    }

    /// One path drawn uniformly among all valid paths (`total() > 0`): the end frame with
    /// weight `dp[L-1][i]`, then each predecessor with weight `dp[k-1][j]`. A path is then
    /// chosen with probability Π (dp[k-1][j] / dp[k][i]) · dp[L-1][end] / total = 1 / total.
    fn draw<R: Rng + ?Sized>(&self, graph: &TransitionGraph, rng: &mut R, out: &mut [u32]) {
        let mut at = pick(&self.end_prefix, rng);
        out[self.length - 1] = at as u32;
        for k in (1..self.length).rev() {
            let prefix = &self.predecessor_prefix[k][at];
            at = graph.predecessors[at][pick(prefix, rng)] as usize;
            out[k - 1] = at as u32;
        }
    }
}

/// The index of a weighted choice given prefix sums (last = total > 0).
fn pick<R: Rng + ?Sized>(prefix: &[u128], rng: &mut R) -> usize {
    let total = prefix.last().copied().unwrap_or(0);
    let r = rng.random_range(0..total.max(1));
    prefix.partition_point(|&s| s <= r)
}

/// Unique sampled paths of one length, stored flat to keep a million of them compact.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SampledPaths {
    length: usize,
    frames: Vec<u32>,
    /// Draws made, including duplicates.
    pub attempts: usize,
}

impl SampledPaths {
    pub fn len(&self) -> usize {
        self.frames.len() / self.length.max(1)
    }

    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The paths in the order they were drawn, as key-frame indices in time order.
    pub fn iter(&self) -> impl Iterator<Item = &[u32]> {
        self.frames.chunks_exact(self.length.max(1))
    }
}

/// ENACT quirk: at most ten draws per path wanted (`max_attempts = num * 10`); duplicates are
/// redrawn, so fewer paths than asked can come back when most paths are already taken.
pub const ATTEMPTS_PER_PATH: usize = 10;

/// Samples `min(wanted, total)` unique paths uniformly (ENACT's `_sample_paths_randomly`),
/// giving up after [`ATTEMPTS_PER_PATH`] draws per wanted path.
pub fn sample_paths<R: Rng + ?Sized>(
    graph: &TransitionGraph,
    table: &PathTable,
    wanted: usize,
    rng: &mut R,
) -> SampledPaths {
    let length = table.length;
    let total = table.total();
    let wanted = (wanted as u128).min(total) as usize;
    let mut frames = Vec::with_capacity(wanted * length);
    let mut seen = SeenPaths::new(graph.frames.len(), length);
    let mut path = vec![0u32; length];
    let mut attempts = 0;
    let max_attempts = wanted.saturating_mul(ATTEMPTS_PER_PATH);
    while frames.len() < wanted * length && attempts < max_attempts {
        attempts += 1;
        table.draw(graph, rng, &mut path);
        if seen.insert(&path) {
            frames.extend_from_slice(&path);
        }
    }
    SampledPaths {
        length,
        frames,
        attempts,
    }
}

/// The set of paths drawn so far. When indices fit in 12 bits and paths have at most ten
/// frames, a path packs losslessly into one u128 (16 bytes per path).
enum SeenPaths {
    Packed(HashSet<u128>),
    Boxed(HashSet<Box<[u32]>>),
}

impl SeenPaths {
    const BITS: usize = 12;

    fn new(frames: usize, length: usize) -> SeenPaths {
        if frames <= 1 << Self::BITS && length * Self::BITS <= 128 {
            SeenPaths::Packed(HashSet::new())
        } else {
            SeenPaths::Boxed(HashSet::new())
        }
    }

    fn insert(&mut self, path: &[u32]) -> bool {
        match self {
            SeenPaths::Packed(set) => set.insert(
                path.iter()
                    .fold(0u128, |key, &i| (key << Self::BITS) | i as u128),
            ),
            SeenPaths::Boxed(set) => set.insert(path.into()),
        }
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    pub(crate) fn names(n: usize) -> Vec<String> {
        (0..n).map(|i| (i * 211 + 59).to_string()).collect()
    }

    /// Every path of `length` frames, by brute force.
    fn enumerate(graph: &TransitionGraph, length: usize) -> Vec<Vec<u32>> {
        let mut paths: Vec<Vec<u32>> = (0..graph.frames.len() as u32).map(|i| vec![i]).collect();
        for _ in 1..length {
            paths = paths
                .into_iter()
                .flat_map(|p| {
                    let last = *p.last().unwrap() as usize;
                    graph.successors(last).iter().map(move |&s| {
                        let mut q = p.clone();
                        q.push(s);
                        q
                    })
                })
                .collect();
        }
        paths
    }

    /// A small irregular DAG: 7 frames, some skips, one frame unreachable.
    pub(crate) fn small_dag() -> TransitionGraph {
        TransitionGraph::from_edges(
            names(7),
            [
                (0, 1),
                (0, 2),
                (0, 4),
                (1, 2),
                (1, 3),
                (2, 3),
                (2, 5),
                (3, 4),
                (3, 5),
                (4, 5),
                (1, 6),
                (5, 6),
            ],
        )
        .unwrap()
    }

    #[test]
    fn counts_equal_brute_force() {
        let g = small_dag();
        for length in 1..=7 {
            let table = PathTable::count(&g, length).unwrap();
            let paths = enumerate(&g, length);
            assert_eq!(table.total(), paths.len() as u128, "length {length}");
            for (i, &c) in table.paths_ending_at().iter().enumerate() {
                let ending = paths.iter().filter(|p| *p.last().unwrap() as usize == i);
                assert_eq!(c, ending.count() as u128);
            }
        }
        assert_eq!(PathTable::count(&g, 1).unwrap().total(), 7);
        assert!(PathTable::count(&g, 0).is_err());
    }

    #[test]
    fn backward_or_out_of_range_edges_are_rejected() {
        assert!(TransitionGraph::from_edges(names(3), [(1, 0)]).is_err());
        assert!(TransitionGraph::from_edges(names(3), [(1, 1)]).is_err());
        assert!(TransitionGraph::from_edges(names(3), [(1, 3)]).is_err());
    }

    #[test]
    fn complete_dag_counts_are_binomials_and_big_ones_do_not_overflow() {
        // A complete DAG on n frames has C(n, L) paths of L frames.
        let complete = |n: usize| {
            let edges = (0..n).flat_map(move |i| (i + 1..n).map(move |j| (i, j)));
            TransitionGraph::from_edges(names(n), edges).unwrap()
        };
        let binomial = |n: u128, k: u128| (0..k).fold(1u128, |acc, i| acc * (n - i) / (i + 1));
        let g = complete(300);
        for length in 3..=10 {
            let t = PathTable::count(&g, length).unwrap();
            assert_eq!(t.total(), binomial(300, length as u128));
        }
        // C(300, 10) ≈ 1.4·10^18 is close to u64::MAX; past it, u128 is still exact.
        let g = complete(1000);
        assert_eq!(
            PathTable::count(&g, 10).unwrap().total(),
            binomial(1000, 10)
        );
        assert!(binomial(1000, 10) > u64::MAX as u128);
    }

    #[test]
    fn samples_are_unique_valid_and_capped() {
        let g = small_dag();
        let table = PathTable::count(&g, 4).unwrap();
        let all = enumerate(&g, 4);
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let s = sample_paths(&g, &table, 1000, &mut rng);
        // Every path is found (min(wanted, total)), none twice, each valid.
        assert_eq!(s.len(), all.len());
        let got: HashSet<Vec<u32>> = s.iter().map(<[u32]>::to_vec).collect();
        assert_eq!(got.len(), all.len());
        for p in s.iter() {
            assert!(all.contains(&p.to_vec()));
        }
        assert!(s.attempts <= all.len() * ATTEMPTS_PER_PATH);
        // The same seed gives the same paths.
        let again = sample_paths(&g, &table, 1000, &mut ChaCha8Rng::seed_from_u64(7));
        assert_eq!(again, s);
        // A graph without long paths yields nothing.
        assert_eq!(PathTable::count(&g, 7).unwrap().total(), 1);
        let empty = PathTable::count(&g, 8).unwrap();
        assert_eq!(empty.total(), 0);
        assert!(sample_paths(&g, &empty, 5, &mut rng).is_empty());
    }

    #[test]
    fn boxed_seen_set_for_many_frames() {
        let edges = (0..5000).map(|i| (i, i + 1));
        let g = TransitionGraph::from_edges(names(5001), edges).unwrap();
        let t = PathTable::count(&g, 3).unwrap();
        assert_eq!(t.total(), 4999);
        let s = sample_paths(&g, &t, 100, &mut ChaCha8Rng::seed_from_u64(1));
        assert_eq!(s.len(), 100);
        for p in s.iter() {
            assert_eq!((p[1] - p[0], p[2] - p[1]), (1, 1));
        }
    }

    /// The sampler draws every valid path equally often (chi-square goodness of fit).
    /// Checked to fail when biased: weighting the end frame by 1 instead of dp gives
    /// chi-square ≈ 1,700 with this seed.
    #[test]
    fn draws_are_uniform_over_all_paths() {
        let g = small_dag();
        let table = PathTable::count(&g, 3).unwrap();
        let all = enumerate(&g, 3);
        let k = all.len();
        assert_eq!(k, 16);
        let draws = 200 * k;
        let mut counts = vec![0usize; k];
        let mut rng = ChaCha8Rng::seed_from_u64(2024);
        let mut path = vec![0u32; 3];
        for _ in 0..draws {
            table.draw(&g, &mut rng, &mut path);
            let at = all.iter().position(|p| *p == path).expect("a valid path");
            counts[at] += 1;
        }
        let expected = draws as f64 / k as f64;
        let chi2: f64 = counts
            .iter()
            .map(|&c| (c as f64 - expected).powi(2) / expected)
            .sum();
        // 15 degrees of freedom: the 0.999 quantile is 37.70.
        assert!(chi2 < 37.70, "chi-square {chi2} over {k} paths: {counts:?}");
    }
}
