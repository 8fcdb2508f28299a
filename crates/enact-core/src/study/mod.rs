//! Ablation studies (the paper's sections 3.2–3.4 and appendix C): a baseline dataset and
//! variant datasets that ask the same questions with other images (rendering, camera,
//! embodiment), grouped in families. A study report compares one model's per-item pairwise
//! accuracy on each variant with its accuracy on the baseline.
//!
//! - this module: naming rules, the `FAMILY/LABEL=DATASET` variant syntax, and [`align`],
//!   which pairs a variant's items with the baseline's;
//! - [`stats`]: the paired t and sign tests reported beside the paper's Welch test;
//! - [`report`]: the report's cells and handedness rows; [`figure`] the heatmap's panels;
//!   [`export`] its files (JSON, CSV, LaTeX, SVG);
//! - [`subset`]: stratified subsets of a dataset, variants that keep the source's items;
//! - [`table`]: the report in the layout of the paper's appendix tables (TA and PA per
//!   setting, direction and step length; mean ± sd over a family's seeds).

pub mod export;
pub mod figure;
pub mod report;
pub mod stats;
pub mod subset;
pub mod table;

use std::collections::{BTreeMap, HashMap, HashSet};

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

use crate::scoring::ScoringItem;

/// Longest study name, family or variant label, in characters.
pub const MAX_NAME_CHARS: usize = 64;
/// Most variants in one study.
pub const MAX_VARIANTS: usize = 64;

/// A study's name, trimmed: it appears in URLs and file names, so it stays plain (1 to 64
/// letters, digits, `.`, `_` and `-`).
pub fn study_name(name: &str) -> Result<&str, String> {
    crate::credentials::plain_name(name, "study", MAX_NAME_CHARS)
}

/// One variant of a study: its family ("Camera FOV"), its label in the family ("Aperture 30")
/// and the dataset that holds it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
pub struct VariantSpec {
    pub family: String,
    pub label: String,
    pub dataset: String,
}

fn label_part(what: &str, text: &str, spec: &str) -> Result<String, String> {
    let text = text.trim();
    if text.is_empty() || text.chars().count() > MAX_NAME_CHARS {
        return Err(format!(
            "variant {spec:?}: the {what} has 1 to {MAX_NAME_CHARS} characters"
        ));
    }
    if text.chars().any(char::is_control) {
        return Err(format!(
            "variant {spec:?}: the {what} has a control character"
        ));
    }
    Ok(text.to_owned())
}

impl VariantSpec {
    /// Checks and trims the three parts, naming the one that is wrong.
    pub fn new(family: &str, label: &str, dataset: &str) -> Result<VariantSpec, String> {
        let spec = format!("{family}/{label}={dataset}");
        let dataset = dataset.trim();
        if dataset.is_empty() {
            return Err(format!("variant {spec:?}: the dataset name is empty"));
        }
        Ok(VariantSpec {
            family: label_part("family", family, &spec)?,
            label: label_part("label", label, &spec)?,
            dataset: dataset.to_owned(),
        })
    }

    /// Reads `FAMILY/LABEL=DATASET` (`Camera FOV/Aperture 30=fov30`): the family is before the
    /// first `/`, the dataset after the last `=`.
    pub fn parse(text: &str) -> Result<VariantSpec, String> {
        let Some((left, dataset)) = text.rsplit_once('=') else {
            return Err(format!(
                "variant {text:?}: expected FAMILY/LABEL=DATASET (no '=' found)"
            ));
        };
        let Some((family, label)) = left.split_once('/') else {
            return Err(format!(
                "variant {text:?}: expected FAMILY/LABEL=DATASET (no '/' before the '=')"
            ));
        };
        VariantSpec::new(family, label, dataset)
    }
}

/// Checks a study's variants as a whole: at least one, at most [`MAX_VARIANTS`], no family and
/// label twice, no dataset twice, none the baseline itself.
pub fn check_variants(baseline: &str, variants: &[VariantSpec]) -> Result<(), String> {
    if variants.is_empty() {
        return Err("a study needs at least one variant".to_owned());
    }
    if variants.len() > MAX_VARIANTS {
        return Err(format!(
            "{} variants; a study has at most {MAX_VARIANTS}",
            variants.len()
        ));
    }
    let mut labels = HashSet::new();
    let mut datasets = HashSet::new();
    for v in variants {
        if v.dataset == baseline {
            return Err(format!(
                "variant {}/{}: dataset '{}' is the baseline",
                v.family, v.label, v.dataset
            ));
        }
        if !labels.insert((&v.family, &v.label)) {
            return Err(format!("variant {}/{} is named twice", v.family, v.label));
        }
        if !datasets.insert(&v.dataset) {
            return Err(format!("dataset '{}' is given for two variants", v.dataset));
        }
    }
    Ok(())
}

/// Families in the order their first variant was given, each with its variants in order.
pub fn families(variants: &[VariantSpec]) -> Vec<(&str, Vec<&VariantSpec>)> {
    let mut order: Vec<(&str, Vec<&VariantSpec>)> = Vec::new();
    for v in variants {
        match order.iter_mut().find(|(family, _)| *family == v.family) {
            Some((_, members)) => members.push(v),
            None => order.push((&v.family, vec![v])),
        }
    }
    order
}

/// What alignment reads of an item.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct AlignKey {
    pub item_id: String,
    pub item_type: String,
    pub task_name: String,
    pub key_frame_ids: Vec<String>,
    /// [`verification_fingerprint`] of the item: aligned items with different ones are scored
    /// by different rules.
    pub verification: String,
}

impl AlignKey {
    /// What alignment reads of a stored item.
    pub fn of_stored(item: ScoringItem) -> AlignKey {
        let gt: Vec<String> = item.gt_answer.iter().map(u8::to_string).collect();
        let verification = verification_fingerprint(
            &gt.join(","),
            item.semantics
                .as_ref()
                .map(|(source, table)| (source.as_str(), table.as_str())),
        );
        AlignKey {
            item_id: item.item_id,
            item_type: item.item_type,
            task_name: item.task_name,
            key_frame_ids: item.key_frame_ids,
            verification,
        }
    }
}

/// A fingerprint of how an item's answers are judged: its ground truth and its signature table
/// (`(source, table)` as stored), sha256 in hex.
pub fn verification_fingerprint(gt_answer: &str, signatures: Option<(&str, &str)>) -> String {
    use sha2::{Digest, Sha256};
    let mut hasher = Sha256::new();
    hasher.update(gt_answer.as_bytes());
    match signatures {
        Some((source, table)) => {
            hasher.update(b"\0");
            hasher.update(source.as_bytes());
            hasher.update(b"\0");
            hasher.update(table.as_bytes());
        }
        None => hasher.update(b"\0exact match only"),
    }
    hex::encode(hasher.finalize())
}

/// Which variant item answers which baseline item.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, JsonSchema)]
pub struct Alignment {
    /// (baseline index, variant index) into the slices given to [`align`], in baseline order.
    #[serde(skip)]
    pub pairs: Vec<(usize, usize)>,
    /// Pairs with the same id (and the same task and type).
    pub by_id: usize,
    /// Pairs found by task, type and key frames where the ids differ.
    pub by_key_frames: usize,
    /// Baseline items with no partner.
    pub baseline_unaligned: usize,
    /// Variant items with no partner.
    pub variant_unaligned: usize,
    /// Items left unaligned because their task, type and key frames match several items.
    pub ambiguous: usize,
    /// Aligned pairs judged by different rules (another ground truth or another signature
    /// table): their scores differ for reasons other than the images. A variant made with
    /// `generate --items-from` and imported with the baseline's scene graphs has none.
    pub verified_differently: usize,
}

impl Alignment {
    pub fn aligned(&self) -> usize {
        self.pairs.len()
    }
}

/// Pairs a variant's items with the baseline's: first by id (the same task and type too), then
/// the rest by task, type and key frame ids where exactly one item on each side has them.
pub fn align(baseline: &[AlignKey], variant: &[AlignKey]) -> Alignment {
    let by_id: HashMap<&str, usize> = variant
        .iter()
        .enumerate()
        .map(|(i, k)| (k.item_id.as_str(), i))
        .collect();
    let mut partner: Vec<Option<usize>> = vec![None; baseline.len()];
    let mut taken = vec![false; variant.len()];
    let mut alignment = Alignment::default();
    for (b, key) in baseline.iter().enumerate() {
        if let Some(&v) = by_id.get(key.item_id.as_str())
            && variant[v].item_type == key.item_type
            && variant[v].task_name == key.task_name
        {
            partner[b] = Some(v);
            taken[v] = true;
            alignment.by_id += 1;
        }
    }
    // Task, type and key frames, borrowed.
    type Content<'a> = (&'a str, &'a str, &'a [String]);
    fn content(k: &AlignKey) -> Content<'_> {
        (&k.task_name, &k.item_type, &k.key_frame_ids)
    }
    let mut open_variant: BTreeMap<Content<'_>, Vec<usize>> = BTreeMap::new();
    for (v, key) in variant.iter().enumerate().filter(|(v, _)| !taken[*v]) {
        open_variant.entry(content(key)).or_default().push(v);
    }
    let mut open_baseline: BTreeMap<Content<'_>, Vec<usize>> = BTreeMap::new();
    for (b, key) in baseline
        .iter()
        .enumerate()
        .filter(|(b, _)| partner[*b].is_none())
    {
        open_baseline.entry(content(key)).or_default().push(b);
    }
    for (key, bs) in &open_baseline {
        match (bs.as_slice(), open_variant.get(key).map(Vec::as_slice)) {
            ([b], Some([v])) => {
                partner[*b] = Some(*v);
                taken[*v] = true;
                alignment.by_key_frames += 1;
            }
            (_, Some(vs)) => alignment.ambiguous += bs.len() + vs.len(),
            (_, None) => {}
        }
    }
    alignment.pairs = partner
        .iter()
        .enumerate()
        .filter_map(|(b, v)| v.map(|v| (b, v)))
        .collect();
    alignment.verified_differently = alignment
        .pairs
        .iter()
        .filter(|&&(b, v)| baseline[b].verification != variant[v].verification)
        .count();
    alignment.baseline_unaligned = baseline.len() - alignment.pairs.len();
    alignment.variant_unaligned = variant.len() - alignment.pairs.len();
    alignment
}

#[cfg(test)]
mod tests {
    use super::*;

    fn key(id: &str, task: &str, frames: &[&str]) -> AlignKey {
        AlignKey {
            item_id: id.to_owned(),
            item_type: "forward_world_modeling_3_steps".to_owned(),
            task_name: task.to_owned(),
            key_frame_ids: frames.iter().map(|f| (*f).to_owned()).collect(),
            verification: verification_fingerprint("[1, 2]", Some(("scene_graph", "{}"))),
        }
    }

    #[test]
    fn variant_specs_parse_and_name_their_problems() {
        let v = VariantSpec::parse(" Camera FOV / Aperture 30 = fov30 ").unwrap();
        assert_eq!(
            (v.family.as_str(), v.label.as_str(), v.dataset.as_str()),
            ("Camera FOV", "Aperture 30", "fov30")
        );
        // The label may hold '/', the family may not; the dataset is after the last '='.
        let v = VariantSpec::parse("Realism/Ray tracing/only=a=b").unwrap();
        assert_eq!(
            (v.label.as_str(), v.dataset.as_str()),
            ("Ray tracing/only=a", "b")
        );
        assert!(
            VariantSpec::parse("Camera=fov")
                .unwrap_err()
                .contains("no '/'")
        );
        assert!(
            VariantSpec::parse("Camera/fov")
                .unwrap_err()
                .contains("no '='")
        );
        assert!(
            VariantSpec::parse("/x=d")
                .unwrap_err()
                .contains("the family")
        );
        assert!(
            VariantSpec::parse("f/x=")
                .unwrap_err()
                .contains("dataset name is empty")
        );
        assert!(study_name("fov study").unwrap_err().contains("' '"));
        assert_eq!(study_name(" fov-1 ").unwrap(), "fov-1");
    }

    #[test]
    fn variant_lists_are_checked_as_a_whole() {
        let v = |f: &str, l: &str, d: &str| VariantSpec::new(f, l, d).unwrap();
        assert!(
            check_variants("base", &[])
                .unwrap_err()
                .contains("at least one")
        );
        assert!(
            check_variants("base", &[v("a", "b", "base")])
                .unwrap_err()
                .contains("is the baseline")
        );
        assert!(
            check_variants("base", &[v("a", "b", "d1"), v("a", "b", "d2")])
                .unwrap_err()
                .contains("named twice")
        );
        assert!(
            check_variants("base", &[v("a", "b", "d1"), v("a", "c", "d1")])
                .unwrap_err()
                .contains("two variants")
        );
        let list = [
            v("Cam", "30", "d1"),
            v("Real", "RT", "d2"),
            v("Cam", "80", "d3"),
        ];
        check_variants("base", &list).unwrap();
        let grouped = families(&list);
        assert_eq!(grouped.len(), 2);
        assert_eq!(grouped[0].0, "Cam");
        assert_eq!(grouped[0].1.len(), 2);
    }

    #[test]
    fn items_align_by_id_then_by_key_frames() {
        let baseline = [
            key("a", "t1", &["1", "5"]),
            key("b", "t1", &["5", "9"]),
            key("c", "t2", &["1", "2"]),
            key("d", "t2", &["3", "4"]),
            key("e", "t2", &["3", "4"]),
        ];
        let variant = [
            key("b", "t1", &["5", "9"]),
            key("x", "t1", &["1", "5"]),
            key("a", "t9", &["7", "8"]),
            key("y", "t2", &["3", "4"]),
        ];
        let a = align(&baseline, &variant);
        // b by id; a by key frames (its id names another task's item in the variant);
        // d and e share their key frames with each other and y: ambiguous.
        assert_eq!(a.pairs, vec![(0, 1), (1, 0)]);
        assert_eq!((a.by_id, a.by_key_frames, a.ambiguous), (1, 1, 3));
        assert_eq!((a.baseline_unaligned, a.variant_unaligned), (3, 2));
        assert_eq!(a.verified_differently, 0);
        // The same item judged by other signatures (its variant's own scene graphs).
        let mut other = variant.clone();
        other[0].verification = verification_fingerprint("[1, 2]", Some(("scene_graph", "[]")));
        assert_eq!(align(&baseline, &other).verified_differently, 1);
        assert_ne!(
            verification_fingerprint("[1, 2]", None),
            verification_fingerprint("[2, 1]", None)
        );
    }
}
