//! The true and predicted component sets of each step of an answer, from the item's signature
//! table: the sets ENACT writes as `correct_signatures` / `input_signatures` when asked to
//! analyse wrong cases.
//!
//! - Forward: step k of the truth is the visible change C_k between key frames k and k+1; the
//!   predicted step is the visible change between the frames the answer puts at k and k+1
//!   (the first is always the current state). The verifier accepts the step when C_k is a
//!   subset of the predicted frames' full change.
//! - Inverse: step j of the truth is C_j; the predicted step is the visible change of the
//!   transition the chosen action really caused. The verifier accepts it when that set is a
//!   subset of the full change F_j.
//!
//! Only answers that are permutations of the right length get here (the paper analyses equal
//! lengths only), so every label names one key frame or one action.

use crate::verifier::{Direction, ItemSignatures, Permutation, View};

use super::component::{Component, ComponentParseError};

/// One step of an answer.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct StepSets {
    pub truth: Vec<Component>,
    pub predicted: Vec<Component>,
    /// Whether the verifier's per-step test passes (the step counts toward pairwise accuracy).
    pub accepted: bool,
}

/// Why an answer's steps cannot be compared.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum StepsUnavailable {
    #[error("the answer has {answer} labels, the item {truth}")]
    Length { answer: usize, truth: usize },
    #[error("the item's signature table has no {view:?} set for key frames {from} → {to}")]
    NotCovered { view: View, from: usize, to: usize },
    #[error("ENACT cannot compute the change between key frames {from} and {to}: {message}")]
    Raised {
        from: usize,
        to: usize,
        message: String,
    },
    #[error(transparent)]
    Signature(#[from] ComponentParseError),
}

fn set(
    table: &ItemSignatures,
    view: View,
    from: usize,
    to: usize,
) -> Result<Vec<&str>, StepsUnavailable> {
    match table.signature_set(view, from, to) {
        None => Err(StepsUnavailable::NotCovered { view, from, to }),
        Some(Err(message)) => Err(StepsUnavailable::Raised {
            from,
            to,
            message: message.to_owned(),
        }),
        Some(Ok(set)) => Ok(set),
    }
}

fn components(signatures: &[&str]) -> Result<Vec<Component>, StepsUnavailable> {
    Ok(signatures
        .iter()
        .map(|s| Component::parse(s))
        .collect::<Result<_, _>>()?)
}

fn is_subset(a: &[&str], b: &[&str]) -> bool {
    // Both come sorted from the table.
    a.iter().all(|s| b.binary_search(s).is_ok())
}

/// The steps of `answer` for an item with ground truth `truth` and signature table `table`.
pub fn answer_steps(
    direction: Direction,
    truth: &Permutation,
    answer: &Permutation,
    table: &ItemSignatures,
) -> Result<Vec<StepSets>, StepsUnavailable> {
    let n = truth.len();
    if answer.len() != n {
        return Err(StepsUnavailable::Length {
            answer: answer.len(),
            truth: n,
        });
    }
    // position[label] = the chronological index (0-based) of the transition that label names
    // in the truth: for forward the key frame it shows is position + 1.
    let mut position = vec![0usize; n + 1];
    for (i, &label) in truth.labels().iter().enumerate() {
        position[usize::from(label)] = i;
    }
    let mut steps = Vec::with_capacity(n);
    match direction {
        Direction::Forward => {
            let mut frame = 0;
            for (k, &label) in answer.labels().iter().enumerate() {
                let next = position[usize::from(label)] + 1;
                let truth_set = set(table, View::Visible, k, k + 1)?;
                let predicted = set(table, View::Visible, frame, next)?;
                let predicted_full = set(table, View::Full, frame, next)?;
                steps.push(StepSets {
                    truth: components(&truth_set)?,
                    predicted: components(&predicted)?,
                    accepted: is_subset(&truth_set, &predicted_full),
                });
                frame = next;
            }
        }
        Direction::Inverse => {
            for (j, &label) in answer.labels().iter().enumerate() {
                let caused = position[usize::from(label)];
                let truth_set = set(table, View::Visible, j, j + 1)?;
                let truth_full = set(table, View::Full, j, j + 1)?;
                let predicted = set(table, View::Visible, caused, caused + 1)?;
                steps.push(StepSets {
                    truth: components(&truth_set)?,
                    predicted: components(&predicted)?,
                    accepted: is_subset(&predicted, &truth_full),
                });
            }
        }
    }
    Ok(steps)
}
