//! The built-in demo dataset: a small ENACT-format release generated from a simulated kitchen,
//! so that `enact-hub serve --demo` works without downloading anything.
//!
//! [`write_demo_release`] is the only entry point. It plays three scripted household
//! activities on an explicit predicate state (`world`), derives each transition's action text
//! from the state diff (`diff`, `narration`), draws every key frame (`kitchen`), and writes
//! forward and inverse ordering items for every L in 3..=10 exactly as ENACT lays out a release:
//! `QA/enact_ordering.jsonl` plus `QA/images/{type}/{task_name}/{id}_*.png` (`release`).
//! The generator is self-contained so it can later be swapped for a simulated household world
//! run through the real data pipeline.

mod diff;
mod kitchen;
pub(crate) mod label;
mod narration;
mod paint;
pub(crate) mod prompt;
mod release;
mod world;

use std::path::{Path, PathBuf};

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::demo::label::LabelFont;
use crate::demo::release::{TaskRun, build_items, write_release};

/// What [`write_demo_release`] wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DemoSummary {
    /// `out_dir/QA/enact_ordering.jsonl`.
    pub jsonl_path: PathBuf,
    /// JSONL rows written.
    pub items: usize,
    pub forward_items: usize,
    pub inverse_items: usize,
    /// PNG files written (one per image path in the JSONL).
    pub images: usize,
    /// Task names (`{activity}_{16 digits}`) the items come from.
    pub task_names: Vec<String>,
}

/// Why the demo release could not be written.
#[derive(Debug, thiserror::Error)]
pub enum DemoError {
    #[error("cannot write {path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("cannot encode the PNG {path}: {source}")]
    EncodePng {
        path: PathBuf,
        #[source]
        source: image::ImageError,
    },
    #[error("cannot serialise item {id}: {source}")]
    Serialize {
        id: String,
        #[source]
        source: serde_json::Error,
    },
    #[error("the bundled label font assets/fonts/DejaVuSans-Bold.ttf is unreadable: {0}")]
    Font(#[from] ab_glyph::InvalidFont),
    #[error("demo activity {activity}, step {step}: {reason}")]
    Script {
        activity: &'static str,
        step: usize,
        reason: String,
    },
    #[error("item {id}: key frames {from} and {to} show the same world, so there is no action")]
    Unchanged { id: String, from: usize, to: usize },
    #[error("the demo activities have too few distinct key-frame sequences for {qa_type}")]
    NotEnoughSequences { qa_type: String },
}

/// The seed `serve --demo` uses, so every demo start shows the same dataset.
pub const DEFAULT_SEED: u64 = 42;

/// Writes the demo release under `out_dir` (created if missing; files already there are
/// overwritten). The same seed always gives byte-identical files.
pub fn write_demo_release(out_dir: &Path, seed: u64) -> Result<DemoSummary, DemoError> {
    let font = LabelFont::load()?;
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let runs = world::activities()
        .iter()
        .map(|activity| TaskRun::record(activity, &mut rng))
        .collect::<Result<Vec<_>, _>>()?;
    let items = build_items(&runs, &mut rng)?;
    write_release(out_dir, &runs, &items, &font)
}
