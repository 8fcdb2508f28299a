//! The demo kitchen's world: the objects in it, the explicit predicate state, and the scripted
//! activities whose steps change that state.
//!
//! Everything downstream (action text, pictures, answers) is derived from [`WorldState`], so a
//! step that changes nothing in it could never produce a visible or describable change.

use std::collections::{BTreeMap, BTreeSet};
use std::fmt;

/// One object of the demo kitchen, named as a BEHAVIOR scene graph would name an instance.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum Thing {
    Robot,
    Fridge,
    Stove,
    Counter,
    Shelf,
    CuttingBoard,
    Plate,
    Pan,
    Apple,
    HalfApple1,
    HalfApple2,
    Bread,
    Mug,
    Bacon,
    Knife,
}

impl Thing {
    /// Furniture and the robot: present in every state of every activity.
    pub(crate) const FIXED: [Thing; 7] = [
        Thing::Robot,
        Thing::Fridge,
        Thing::Stove,
        Thing::Counter,
        Thing::Shelf,
        Thing::CuttingBoard,
        Thing::Plate,
    ];

    /// The object as ENACT's `_format_object_name` would print its instance name
    /// (`robot_r1` → "the robot r1", `half_apple_2` → "the half apple").
    pub(crate) fn phrase(self) -> &'static str {
        match self {
            Thing::Robot => "the robot r1",
            Thing::Fridge => "the fridge",
            Thing::Stove => "the stove",
            Thing::Counter => "the countertop",
            Thing::Shelf => "the shelf",
            Thing::CuttingBoard => "the chopping board",
            Thing::Plate => "the plate",
            Thing::Pan => "the frying pan",
            Thing::Apple => "the apple",
            Thing::HalfApple1 | Thing::HalfApple2 => "the half apple",
            Thing::Bread => "the bread",
            Thing::Mug => "the mug",
            Thing::Bacon => "the bacon",
            Thing::Knife => "the carving knife",
        }
    }

    /// Object category; two instances of one category make their relations ambiguous in text.
    pub(crate) fn category(self) -> &'static str {
        match self {
            Thing::HalfApple1 | Thing::HalfApple2 => "half_apple",
            other => other.phrase().trim_start_matches("the "),
        }
    }

    /// Whether the object is a piece cut from another one (ENACT treats "half" objects specially).
    pub(crate) fn is_half(self) -> bool {
        matches!(self, Thing::HalfApple1 | Thing::HalfApple2)
    }

    /// Whether other objects can be put on top of this one.
    fn is_surface(self) -> bool {
        matches!(
            self,
            Thing::Counter
                | Thing::Shelf
                | Thing::CuttingBoard
                | Thing::Plate
                | Thing::Pan
                | Thing::Stove
        )
    }
}

/// One of the robot's two grippers.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum Gripper {
    Left,
    Right,
}

/// Where a movable object is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub(crate) enum Placement {
    OnTop(Thing),
    Inside(Thing),
    HeldBy(Gripper),
}

/// The complete predicate state of the kitchen at one key frame.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct WorldState {
    /// Every movable object that currently exists, with where it is.
    pub(crate) placements: BTreeMap<Thing, Placement>,
    pub(crate) fridge_open: bool,
    pub(crate) stove_on: bool,
    /// Food that has been cooked.
    pub(crate) cooked: BTreeSet<Thing>,
    /// Objects that were cut into pieces, with the pieces they became (the pieces' parent).
    pub(crate) parents: BTreeMap<Thing, Thing>,
}

/// One scripted robot step (or, for `Cook`, the world's response to heat).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Step {
    OpenFridge,
    CloseFridge,
    TurnOnStove,
    TurnOffStove,
    Grasp(Gripper, Thing),
    Place(Gripper, Placement),
    Cook(Thing),
    /// Cut an apple lying on the chopping board into two halves with a held knife.
    SliceApple,
}

impl fmt::Display for Step {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{self:?}")
    }
}

/// Why a scripted step cannot happen in the state it is applied to.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("step {step} is impossible: {reason}")]
pub(crate) struct StepRejected {
    pub(crate) step: String,
    pub(crate) reason: &'static str,
}

impl WorldState {
    fn new(placements: &[(Thing, Placement)]) -> Self {
        WorldState {
            placements: placements.iter().copied().collect(),
            fridge_open: false,
            stove_on: false,
            cooked: BTreeSet::new(),
            parents: BTreeMap::new(),
        }
    }

    /// Whether an object exists in this state (fixed furniture always does).
    pub(crate) fn exists(&self, thing: Thing) -> bool {
        Thing::FIXED.contains(&thing) || self.placements.contains_key(&thing)
    }

    /// The object held by a gripper, if any.
    pub(crate) fn held_by(&self, gripper: Gripper) -> Option<Thing> {
        self.placements
            .iter()
            .find(|(_, p)| **p == Placement::HeldBy(gripper))
            .map(|(t, _)| *t)
    }

    /// Whether `thing` rests, directly or through a stack, on `support`.
    fn rests_on(&self, thing: Thing, support: Thing) -> bool {
        let mut current = thing;
        // A stack is at most as tall as the number of objects, so this always ends.
        for _ in 0..=self.placements.len() {
            match self.placements.get(&current) {
                Some(Placement::OnTop(below)) if *below == support => return true,
                Some(Placement::OnTop(below)) => current = *below,
                _ => return false,
            }
        }
        false
    }

    /// The state after `step`, or why the step cannot happen here.
    pub(crate) fn apply(&self, step: Step) -> Result<WorldState, StepRejected> {
        let reject = |reason| StepRejected {
            step: step.to_string(),
            reason,
        };
        let mut next = self.clone();
        match step {
            Step::OpenFridge if self.fridge_open => return Err(reject("the fridge is open")),
            Step::OpenFridge => next.fridge_open = true,
            Step::CloseFridge if !self.fridge_open => return Err(reject("the fridge is closed")),
            Step::CloseFridge => next.fridge_open = false,
            Step::TurnOnStove if self.stove_on => return Err(reject("the stove is on")),
            Step::TurnOnStove => next.stove_on = true,
            Step::TurnOffStove if !self.stove_on => return Err(reject("the stove is off")),
            Step::TurnOffStove => next.stove_on = false,
            Step::Grasp(gripper, thing) => {
                let Some(placement) = self.placements.get(&thing) else {
                    return Err(reject("the object does not exist"));
                };
                if self.held_by(gripper).is_some() {
                    return Err(reject("the gripper is not empty"));
                }
                match placement {
                    Placement::HeldBy(_) => return Err(reject("the object is already held")),
                    Placement::Inside(Thing::Fridge) if !self.fridge_open => {
                        return Err(reject("the object is in the closed fridge"));
                    }
                    _ => {}
                }
                next.placements.insert(thing, Placement::HeldBy(gripper));
            }
            Step::Place(gripper, target) => {
                let Some(thing) = self.held_by(gripper) else {
                    return Err(reject("the gripper holds nothing"));
                };
                match target {
                    Placement::HeldBy(_) => return Err(reject("placing must put the object down")),
                    Placement::Inside(Thing::Fridge) if !self.fridge_open => {
                        return Err(reject("the fridge is closed"));
                    }
                    Placement::Inside(Thing::Fridge) => {}
                    Placement::Inside(_) => return Err(reject("only the fridge holds things")),
                    Placement::OnTop(support) => {
                        if !support.is_surface() || !self.exists(support) {
                            return Err(reject("the target is not a surface in the scene"));
                        }
                        if support == thing || self.rests_on(support, thing) {
                            return Err(reject("an object cannot be put on itself"));
                        }
                        if matches!(self.placements.get(&support), Some(Placement::HeldBy(_))) {
                            return Err(reject("the target is being carried"));
                        }
                    }
                }
                next.placements.insert(thing, target);
            }
            Step::Cook(food) => {
                if self.cooked.contains(&food) {
                    return Err(reject("the food is already cooked"));
                }
                let heated = self.stove_on
                    && self.rests_on(food, Thing::Pan)
                    && self.placements.get(&Thing::Pan) == Some(&Placement::OnTop(Thing::Stove));
                if !heated {
                    return Err(reject("the food is not in a pan on a lit stove"));
                }
                next.cooked.insert(food);
            }
            Step::SliceApple => {
                let on_board = self.placements.get(&Thing::Apple)
                    == Some(&Placement::OnTop(Thing::CuttingBoard));
                if !on_board {
                    return Err(reject("the apple is not on the chopping board"));
                }
                let knife_held = matches!(
                    self.placements.get(&Thing::Knife),
                    Some(Placement::HeldBy(_))
                );
                if !knife_held {
                    return Err(reject("no gripper holds the knife"));
                }
                next.placements.remove(&Thing::Apple);
                for half in [Thing::HalfApple1, Thing::HalfApple2] {
                    next.placements
                        .insert(half, Placement::OnTop(Thing::CuttingBoard));
                    next.parents.insert(half, Thing::Apple);
                }
            }
        }
        Ok(next)
    }
}

/// A scripted household activity: a start state and the steps the robot performs.
pub(crate) struct Activity {
    /// Activity name in BEHAVIOR's style; the task name adds a 16-digit timestamp.
    pub(crate) name: &'static str,
    pub(crate) start: WorldState,
    pub(crate) steps: Vec<Step>,
}

impl Activity {
    /// Every key-frame state of the activity, the start state first.
    pub(crate) fn states(&self) -> Result<Vec<WorldState>, (usize, StepRejected)> {
        let mut states = vec![self.start.clone()];
        for (index, step) in self.steps.iter().enumerate() {
            let last = &states[states.len() - 1];
            let next = last.apply(*step).map_err(|e| (index, e))?;
            states.push(next);
        }
        Ok(states)
    }
}

/// The demo's three activities, each long enough for 10-state items.
pub(crate) fn activities() -> Vec<Activity> {
    use Gripper::{Left, Right};
    use Placement::{Inside, OnTop};
    vec![
        Activity {
            name: "frying_bacon",
            start: WorldState::new(&[
                (Thing::Bacon, Inside(Thing::Fridge)),
                (Thing::Pan, OnTop(Thing::Counter)),
                (Thing::Mug, OnTop(Thing::Shelf)),
            ]),
            steps: vec![
                Step::OpenFridge,
                Step::Grasp(Left, Thing::Bacon),
                Step::CloseFridge,
                Step::Grasp(Right, Thing::Pan),
                Step::Place(Right, OnTop(Thing::Stove)),
                Step::Place(Left, OnTop(Thing::Pan)),
                Step::TurnOnStove,
                Step::Cook(Thing::Bacon),
                Step::TurnOffStove,
                Step::Grasp(Right, Thing::Bacon),
                Step::Place(Right, OnTop(Thing::Plate)),
                Step::Grasp(Left, Thing::Mug),
                Step::Place(Left, OnTop(Thing::Counter)),
            ],
        },
        Activity {
            name: "slicing_an_apple",
            start: WorldState::new(&[
                (Thing::Apple, OnTop(Thing::Counter)),
                (Thing::Knife, OnTop(Thing::Counter)),
                (Thing::Bread, OnTop(Thing::Counter)),
                (Thing::Mug, OnTop(Thing::Shelf)),
            ]),
            steps: vec![
                Step::Grasp(Left, Thing::Apple),
                Step::Place(Left, OnTop(Thing::CuttingBoard)),
                Step::Grasp(Right, Thing::Knife),
                Step::SliceApple,
                Step::Place(Right, OnTop(Thing::Counter)),
                Step::Grasp(Right, Thing::Bread),
                Step::OpenFridge,
                Step::Place(Right, Inside(Thing::Fridge)),
                Step::CloseFridge,
                Step::Grasp(Left, Thing::Mug),
                Step::Place(Left, OnTop(Thing::Counter)),
            ],
        },
        Activity {
            name: "tidying_the_kitchen",
            start: {
                let mut start = WorldState::new(&[
                    (Thing::Pan, OnTop(Thing::Stove)),
                    (Thing::Mug, OnTop(Thing::Counter)),
                    (Thing::Bread, OnTop(Thing::Counter)),
                    (Thing::Apple, OnTop(Thing::CuttingBoard)),
                ]);
                start.stove_on = true;
                start
            },
            steps: vec![
                Step::TurnOffStove,
                Step::Grasp(Right, Thing::Pan),
                Step::Place(Right, OnTop(Thing::Counter)),
                Step::Grasp(Left, Thing::Mug),
                Step::Place(Left, OnTop(Thing::Shelf)),
                Step::OpenFridge,
                Step::Grasp(Right, Thing::Apple),
                Step::Place(Right, Inside(Thing::Fridge)),
                Step::Grasp(Left, Thing::Bread),
                Step::Place(Left, Inside(Thing::Fridge)),
                Step::CloseFridge,
            ],
        },
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_scripted_step_is_possible_and_changes_the_state() {
        for activity in activities() {
            let states = activity
                .states()
                .unwrap_or_else(|(i, e)| panic!("{} step {i}: {e}", activity.name));
            assert!(states.len() >= 10, "{} is too short", activity.name);
            for pair in states.windows(2) {
                assert_ne!(pair[0], pair[1], "{}", activity.name);
            }
        }
    }

    #[test]
    fn impossible_steps_are_rejected() {
        let start = WorldState::new(&[(Thing::Bacon, Placement::Inside(Thing::Fridge))]);
        assert!(
            start
                .apply(Step::Grasp(Gripper::Left, Thing::Bacon))
                .is_err()
        );
        assert!(start.apply(Step::CloseFridge).is_err());
        assert!(start.apply(Step::Cook(Thing::Bacon)).is_err());
        assert!(start.apply(Step::SliceApple).is_err());
        let open = start.apply(Step::OpenFridge).unwrap();
        let held = open
            .apply(Step::Grasp(Gripper::Left, Thing::Bacon))
            .unwrap();
        assert!(
            held.apply(Step::Grasp(Gripper::Left, Thing::Bacon))
                .is_err()
        );
        assert!(
            held.apply(Step::Place(
                Gripper::Right,
                Placement::OnTop(Thing::Counter)
            ))
            .is_err()
        );
        assert_eq!(held.held_by(Gripper::Left), Some(Thing::Bacon));
    }

    #[test]
    fn slicing_replaces_the_apple_by_two_halves_with_it_as_parent() {
        let start = WorldState::new(&[
            (Thing::Apple, Placement::OnTop(Thing::CuttingBoard)),
            (Thing::Knife, Placement::HeldBy(Gripper::Right)),
        ]);
        let sliced = start.apply(Step::SliceApple).unwrap();
        assert!(!sliced.exists(Thing::Apple));
        assert_eq!(sliced.parents.get(&Thing::HalfApple2), Some(&Thing::Apple));
        assert_eq!(
            sliced.placements.get(&Thing::HalfApple1),
            Some(&Placement::OnTop(Thing::CuttingBoard))
        );
    }
}
