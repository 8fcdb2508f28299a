//! The household activities: each a scripted sequence of actions in one room, continued by
//! seeded random actions when a longer trajectory is asked for.

use rand::Rng;
use rand::seq::IndexedRandom;

use crate::world::state::{Action, Hand, Relation, WorldState};
use crate::world::things::*;

/// An activity the world can play.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Activity {
    PutDishesAway,
    MakeTea,
    CookBacon,
    SliceFruit,
    TidyLivingRoom,
}

impl Activity {
    pub const ALL: [Activity; 5] = [
        Activity::PutDishesAway,
        Activity::MakeTea,
        Activity::CookBacon,
        Activity::SliceFruit,
        Activity::TidyLivingRoom,
    ];

    /// The name used in task names and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Activity::PutDishesAway => "put_dishes_away",
            Activity::MakeTea => "make_tea",
            Activity::CookBacon => "cook_bacon",
            Activity::SliceFruit => "slice_fruit",
            Activity::TidyLivingRoom => "tidy_living_room",
        }
    }

    pub fn from_name(name: &str) -> Option<Activity> {
        Activity::ALL.into_iter().find(|a| a.name() == name)
    }

    pub fn room(self) -> Room {
        match self {
            Activity::TidyLivingRoom => Room::LivingRoom,
            _ => Room::Kitchen,
        }
    }

    /// The activity's own actions, as done with the left hand leading.
    pub fn script(self) -> Vec<Action> {
        use Action::*;
        use Hand::{Left as L, Right as R};
        let on = Relation::OnTop;
        match self {
            Activity::PutDishesAway => vec![
                Open { thing: CABINET },
                Grasp {
                    hand: L,
                    thing: BOWL,
                },
                Place {
                    hand: L,
                    relation: Relation::Inside,
                    target: CABINET,
                },
                Grasp {
                    hand: R,
                    thing: PLATE,
                },
                Place {
                    hand: R,
                    relation: Relation::Inside,
                    target: CABINET,
                },
                Grasp {
                    hand: L,
                    thing: MUG,
                },
                Place {
                    hand: L,
                    relation: on,
                    target: COUNTERTOP,
                },
                Close { thing: CABINET },
                Grasp {
                    hand: R,
                    thing: DISHTOWEL,
                },
                Cover {
                    hand: R,
                    target: MUG,
                },
                Open { thing: CABINET },
            ],
            Activity::MakeTea => vec![
                Open { thing: CABINET },
                Grasp {
                    hand: R,
                    thing: MUG,
                },
                Place {
                    hand: R,
                    relation: on,
                    target: COUNTERTOP,
                },
                Close { thing: CABINET },
                Grasp {
                    hand: L,
                    thing: KETTLE,
                },
                Place {
                    hand: L,
                    relation: on,
                    target: STOVE,
                },
                ToggleOn { thing: STOVE },
                ToggleOff { thing: STOVE },
                Grasp {
                    hand: L,
                    thing: KETTLE,
                },
                Pour {
                    hand: L,
                    target: MUG,
                },
                Place {
                    hand: L,
                    relation: on,
                    target: COUNTERTOP,
                },
            ],
            Activity::CookBacon => vec![
                Grasp {
                    hand: R,
                    thing: BACON,
                },
                Place {
                    hand: R,
                    relation: on,
                    target: PAN,
                },
                ToggleOn { thing: STOVE },
                Cook { thing: BACON },
                ToggleOff { thing: STOVE },
                Grasp {
                    hand: L,
                    thing: BACON,
                },
                Place {
                    hand: L,
                    relation: on,
                    target: PLATE,
                },
                Grasp {
                    hand: R,
                    thing: DISHTOWEL,
                },
                Cover {
                    hand: R,
                    target: PLATE,
                },
                Grasp {
                    hand: L,
                    thing: BOWL,
                },
                Place {
                    hand: L,
                    relation: on,
                    target: STOVE,
                },
            ],
            Activity::SliceFruit => vec![
                Grasp {
                    hand: R,
                    thing: KNIFE,
                },
                Slice {
                    hand: R,
                    thing: APPLE,
                },
                Place {
                    hand: R,
                    relation: on,
                    target: COUNTERTOP,
                },
                Grasp {
                    hand: L,
                    thing: BOWL,
                },
                Place {
                    hand: L,
                    relation: on,
                    target: STOVE,
                },
                Grasp {
                    hand: R,
                    thing: KETTLE,
                },
                Pour {
                    hand: R,
                    target: BOWL,
                },
                Place {
                    hand: R,
                    relation: on,
                    target: COUNTERTOP,
                },
                Grasp {
                    hand: L,
                    thing: DISHTOWEL,
                },
                Cover {
                    hand: L,
                    target: BOARD,
                },
            ],
            Activity::TidyLivingRoom => vec![
                ToggleOn { thing: LAMP },
                Grasp {
                    hand: L,
                    thing: REMOTE,
                },
                Place {
                    hand: L,
                    relation: on,
                    target: SOFA,
                },
                Grasp {
                    hand: R,
                    thing: BASKET,
                },
                Place {
                    hand: R,
                    relation: Relation::Under,
                    target: COFFEE_TABLE,
                },
                Grasp {
                    hand: L,
                    thing: BOOK,
                },
                Place {
                    hand: L,
                    relation: on,
                    target: COFFEE_TABLE,
                },
                Grasp {
                    hand: R,
                    thing: BLANKET,
                },
                Cover {
                    hand: R,
                    target: BASKET,
                },
                ToggleOff { thing: LAMP },
            ],
        }
    }

    /// `length` actions (the script's own length when `None`): the script with its hands
    /// swapped or not (seeded), cut short or continued by random possible actions in the
    /// activity's room. Every action is possible where it is played.
    pub fn plan(self, length: Option<usize>, rng: &mut impl Rng) -> Vec<Action> {
        let swap = rng.random_bool(0.5);
        let mut script = self.script();
        if swap {
            for action in &mut script {
                *action = mirrored(*action);
            }
        }
        let length = length.unwrap_or(script.len());
        let mut state = WorldState::initial();
        let mut plan = Vec::with_capacity(length);
        for action in script.into_iter().take(length) {
            if state.apply(&action).is_ok() {
                plan.push(action);
            }
        }
        while plan.len() < length {
            let possible = state.possible_actions(self.room());
            let Some(action) = possible.choose(rng).copied() else {
                break;
            };
            if state.apply(&action).is_ok() {
                plan.push(action);
            }
        }
        plan
    }
}

fn mirrored(action: Action) -> Action {
    let other = |h: Hand| match h {
        Hand::Left => Hand::Right,
        Hand::Right => Hand::Left,
    };
    match action {
        Action::Grasp { hand, thing } => Action::Grasp {
            hand: other(hand),
            thing,
        },
        Action::Place {
            hand,
            relation,
            target,
        } => Action::Place {
            hand: other(hand),
            relation,
            target,
        },
        Action::Cover { hand, target } => Action::Cover {
            hand: other(hand),
            target,
        },
        Action::Slice { hand, thing } => Action::Slice {
            hand: other(hand),
            thing,
        },
        Action::Pour { hand, target } => Action::Pour {
            hand: other(hand),
            target,
        },
        other_action => other_action,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn every_script_plays_from_the_initial_house() {
        for activity in Activity::ALL {
            let mut state = WorldState::initial();
            for (step, action) in activity.script().iter().enumerate() {
                state
                    .apply(action)
                    .unwrap_or_else(|e| panic!("{} step {step} ({action}): {e}", activity.name()));
            }
            assert_eq!(Activity::from_name(activity.name()), Some(activity));
        }
    }

    #[test]
    fn plans_have_the_asked_length() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for activity in Activity::ALL {
            assert_eq!(activity.plan(Some(4), &mut rng).len(), 4);
            assert_eq!(activity.plan(Some(40), &mut rng).len(), 40);
            assert_eq!(activity.plan(None, &mut rng).len(), activity.script().len());
        }
    }
}
