//! The predicate state of the house (what stands on, in or under what, what is open, on,
//! cooked, held, covered or full of water), the robot's actions on it, and the scene graph it
//! gives (BEHAVIOR's node and edge states, without visibility).

use std::fmt;

use crate::scene_graph::{SceneEdge, SceneGraph, SceneNode};
use crate::world::things::{
    self, APPLE, CATALOGUE, KETTLE, PAN, Room, STOVE, ThingId, WATER, halves_of,
};

/// The robot's node name (BEHAVIOR's R1 robot).
pub const ROBOT: &str = "robot_r1";

/// A gripper of the robot.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Hand {
    Left,
    Right,
}

impl Hand {
    pub const BOTH: [Hand; 2] = [Hand::Left, Hand::Right];

    fn index(self) -> usize {
        match self {
            Hand::Left => 0,
            Hand::Right => 1,
        }
    }

    /// The edge state of the robot holding something with this gripper.
    pub fn grasping_state(self) -> &'static str {
        match self {
            Hand::Left => "LeftGrasping",
            Hand::Right => "RightGrasping",
        }
    }
}

impl fmt::Display for Hand {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Hand::Left => "left",
            Hand::Right => "right",
        })
    }
}

/// How an object rests on another thing.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Relation {
    OnTop,
    Inside,
    Under,
}

impl Relation {
    pub fn state(self) -> &'static str {
        match self {
            Relation::OnTop => "OnTop",
            Relation::Inside => "Inside",
            Relation::Under => "Under",
        }
    }
}

/// One action of the robot (or, for cooking, of the world while the robot waits).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Action {
    Grasp {
        hand: Hand,
        thing: ThingId,
    },
    Place {
        hand: Hand,
        relation: Relation,
        target: ThingId,
    },
    /// Lays the cloth held in `hand` over `target`.
    Cover {
        hand: Hand,
        target: ThingId,
    },
    Open {
        thing: ThingId,
    },
    Close {
        thing: ThingId,
    },
    ToggleOn {
        thing: ThingId,
    },
    ToggleOff {
        thing: ThingId,
    },
    /// Cuts `thing` in two with the knife held in `hand`.
    Slice {
        hand: Hand,
        thing: ThingId,
    },
    /// Pours water from the kettle held in `hand` into `target`.
    Pour {
        hand: Hand,
        target: ThingId,
    },
    /// Waits on the hot pan until `thing` is cooked.
    Cook {
        thing: ThingId,
    },
}

impl fmt::Display for Action {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let n = |t: ThingId| CATALOGUE[t].name;
        match *self {
            Action::Grasp { hand, thing } => {
                write!(f, "grasp {} with the {hand} gripper", n(thing))
            }
            Action::Place {
                hand,
                relation,
                target,
            } => write!(
                f,
                "place what the {hand} gripper holds {} {}",
                relation.state(),
                n(target)
            ),
            Action::Cover { hand, target } => {
                write!(
                    f,
                    "cover {} with the cloth in the {hand} gripper",
                    n(target)
                )
            }
            Action::Open { thing } => write!(f, "open {}", n(thing)),
            Action::Close { thing } => write!(f, "close {}", n(thing)),
            Action::ToggleOn { thing } => write!(f, "turn on {}", n(thing)),
            Action::ToggleOff { thing } => write!(f, "turn off {}", n(thing)),
            Action::Slice { hand, thing } => {
                write!(f, "slice {} with the knife in the {hand} gripper", n(thing))
            }
            Action::Pour { hand, target } => {
                write!(
                    f,
                    "pour water from the {hand} gripper's kettle into {}",
                    n(target)
                )
            }
            Action::Cook { thing } => write!(f, "wait until {} is cooked", n(thing)),
        }
    }
}

/// The predicate state of the whole house.
#[derive(Debug, Clone, PartialEq, Eq, Hash)]
pub struct WorldState {
    present: Vec<bool>,
    support: Vec<Option<(Relation, ThingId)>>,
    open: Vec<bool>,
    on: Vec<bool>,
    cooked: Vec<bool>,
    /// Cloth -> the thing it covers.
    covering: Vec<Option<ThingId>>,
    /// Things that contain water.
    water: Vec<bool>,
    hands: [Option<ThingId>; 2],
}

impl WorldState {
    /// The house as every activity finds it.
    pub fn initial() -> WorldState {
        use things::*;
        let n = CATALOGUE.len();
        let mut s = WorldState {
            present: vec![true; n],
            support: vec![None; n],
            open: vec![false; n],
            on: vec![false; n],
            cooked: vec![false; n],
            covering: vec![None; n],
            water: vec![false; n],
            hands: [None, None],
        };
        s.present[HALF_APPLE_0] = false;
        s.present[HALF_APPLE_1] = false;
        for (thing, relation, target) in [
            (PLATE, Relation::OnTop, COUNTERTOP),
            (BOWL, Relation::OnTop, COUNTERTOP),
            (MUG, Relation::Inside, CABINET),
            (BOARD, Relation::OnTop, COUNTERTOP),
            (APPLE, Relation::OnTop, BOARD),
            (KNIFE, Relation::OnTop, COUNTERTOP),
            (PAN, Relation::OnTop, STOVE),
            (BACON, Relation::OnTop, COUNTERTOP),
            (KETTLE, Relation::OnTop, COUNTERTOP),
            (DISHTOWEL, Relation::OnTop, COUNTERTOP),
            (BOOK, Relation::OnTop, SOFA),
            (REMOTE, Relation::OnTop, COFFEE_TABLE),
            (BASKET, Relation::OnTop, COFFEE_TABLE),
            (BLANKET, Relation::OnTop, SOFA),
        ] {
            s.support[thing] = Some((relation, target));
        }
        s.water[KETTLE] = true;
        s
    }

    pub fn is_present(&self, thing: ThingId) -> bool {
        self.present[thing]
    }

    pub fn support(&self, thing: ThingId) -> Option<(Relation, ThingId)> {
        self.support[thing]
    }

    pub fn is_open(&self, thing: ThingId) -> bool {
        self.open[thing]
    }

    pub fn is_on(&self, thing: ThingId) -> bool {
        self.on[thing]
    }

    pub fn is_cooked(&self, thing: ThingId) -> bool {
        self.cooked[thing]
    }

    pub fn has_water(&self, thing: ThingId) -> bool {
        self.water[thing]
    }

    /// The cloth lying over `thing`, if any.
    pub fn covered_by(&self, thing: ThingId) -> Option<ThingId> {
        (0..CATALOGUE.len()).find(|&c| self.covering[c] == Some(thing))
    }

    /// What the cloth `cloth` covers.
    pub fn covers(&self, cloth: ThingId) -> Option<ThingId> {
        self.covering[cloth]
    }

    pub fn held(&self, hand: Hand) -> Option<ThingId> {
        self.hands[hand.index()]
    }

    /// The gripper holding `thing`, if any.
    pub fn holder(&self, thing: ThingId) -> Option<Hand> {
        Hand::BOTH
            .into_iter()
            .find(|h| self.held(*h) == Some(thing))
    }

    /// Whether `thing` is held, directly or by resting on something held.
    pub fn is_carried(&self, thing: ThingId) -> bool {
        let mut at = thing;
        for _ in 0..CATALOGUE.len() {
            if self.holder(at).is_some() {
                return true;
            }
            match self.support[at] {
                Some((_, below)) => at = below,
                None => return false,
            }
        }
        false
    }

    /// Whether `thing` sits inside a closed container (directly or on something that does).
    pub fn is_shut_away(&self, thing: ThingId) -> bool {
        let mut at = thing;
        for _ in 0..CATALOGUE.len() {
            match self.support[at] {
                Some((Relation::Inside, container)) if !self.open[container] => return true,
                Some((_, below)) => at = below,
                None => return false,
            }
        }
        false
    }

    fn things_on(&self, target: ThingId) -> impl Iterator<Item = ThingId> + '_ {
        (0..CATALOGUE.len()).filter(move |&t| {
            self.present[t] && matches!(self.support[t], Some((_, s)) if s == target)
        })
    }

    /// Whether `action` can be done now; `Err` says why not.
    pub fn check(&self, action: &Action) -> Result<(), String> {
        let name = |t: ThingId| CATALOGUE[t].name;
        let free = |h: Hand| self.held(h).is_none();
        let present = |t: ThingId| {
            if self.present[t] {
                Ok(())
            } else {
                Err(format!("{} is not in the house", name(t)))
            }
        };
        let holds = |h: Hand, what: &dyn Fn(ThingId) -> bool, label: &str| match self.held(h) {
            Some(t) if what(t) => Ok(t),
            _ => Err(format!("the {h} gripper holds no {label}")),
        };
        match *action {
            Action::Grasp { hand, thing } => {
                present(thing)?;
                if !free(hand) {
                    return Err(format!("the {hand} gripper is not free"));
                }
                if CATALOGUE[thing].is_furniture() || thing == things::WATER {
                    return Err(format!("{} cannot be carried", name(thing)));
                }
                if self.is_carried(thing) {
                    return Err(format!("{} is already carried", name(thing)));
                }
                if self.is_shut_away(thing) {
                    return Err(format!("{} is in a closed container", name(thing)));
                }
                if self.covered_by(thing).is_some() || self.things_on(thing).next().is_some() {
                    return Err(format!("something lies on {}", name(thing)));
                }
                Ok(())
            }
            Action::Place {
                hand,
                relation,
                target,
            } => {
                let held = holds(hand, &|_| true, "object")?;
                present(target)?;
                if target == held || self.is_carried(target) || self.is_shut_away(target) {
                    return Err(format!("{} cannot take {}", name(target), name(held)));
                }
                let fits = match relation {
                    Relation::OnTop => things::surface_slots(target).is_some(),
                    Relation::Inside => things::is_container(target) && self.open[target],
                    Relation::Under => things::has_room_under(target),
                };
                if !fits || things::is_cloth(held) && relation != Relation::OnTop {
                    return Err(format!(
                        "{} cannot go {} {}",
                        name(held),
                        relation.state(),
                        name(target)
                    ));
                }
                if self.covered_by(target).is_some() {
                    return Err(format!("{} is covered", name(target)));
                }
                Ok(())
            }
            Action::Cover { hand, target } => {
                let cloth = holds(hand, &things::is_cloth, "cloth")?;
                present(target)?;
                let spec = &CATALOGUE[target];
                let coverable = !things::is_cloth(target)
                    && target != WATER
                    && spec.room == CATALOGUE[cloth].room
                    && (!spec.is_furniture() || target == things::SOFA);
                if !coverable
                    || self.is_carried(target)
                    || self.is_shut_away(target)
                    || self.covered_by(target).is_some()
                {
                    return Err(format!("{} cannot be covered", name(target)));
                }
                Ok(())
            }
            Action::Open { thing } | Action::Close { thing } => {
                if !things::is_openable(thing) {
                    return Err(format!("{} does not open", name(thing)));
                }
                if Hand::BOTH.into_iter().all(|h| !free(h)) {
                    return Err("no gripper is free".into());
                }
                let want_open = matches!(action, Action::Open { .. });
                if self.open[thing] == want_open {
                    return Err(format!("{} is already so", name(thing)));
                }
                Ok(())
            }
            Action::ToggleOn { thing } | Action::ToggleOff { thing } => {
                if !things::is_toggleable(thing) {
                    return Err(format!("{} has no switch", name(thing)));
                }
                if Hand::BOTH.into_iter().all(|h| !free(h)) {
                    return Err("no gripper is free".into());
                }
                let want_on = matches!(action, Action::ToggleOn { .. });
                if self.on[thing] == want_on {
                    return Err(format!("{} is already so", name(thing)));
                }
                Ok(())
            }
            Action::Slice { hand, thing } => {
                holds(hand, &|t| t == things::KNIFE, "knife")?;
                present(thing)?;
                if halves_of(thing).is_none() || self.is_carried(thing) || self.is_shut_away(thing)
                {
                    return Err(format!("{} cannot be sliced now", name(thing)));
                }
                if self.covered_by(thing).is_some() {
                    return Err(format!("{} is covered", name(thing)));
                }
                Ok(())
            }
            Action::Pour { hand, target } => {
                holds(hand, &|t| t == KETTLE && self.water[t], "kettle of water")?;
                present(target)?;
                if !things::holds_water(target)
                    || self.water[target]
                    || self.is_shut_away(target)
                    || self.covered_by(target).is_some()
                {
                    return Err(format!("{} cannot take water now", name(target)));
                }
                Ok(())
            }
            Action::Cook { thing } => {
                let hot = self.on[STOVE] && self.support[PAN] == Some((Relation::OnTop, STOVE));
                if !things::is_cookable(thing)
                    || self.cooked[thing]
                    || !hot
                    || self.support[thing] != Some((Relation::OnTop, PAN))
                {
                    return Err(format!("{} is not on a hot pan", name(thing)));
                }
                Ok(())
            }
        }
    }

    /// Does `action` (all of its effects at once), or says why it cannot be done.
    pub fn apply(&mut self, action: &Action) -> Result<(), String> {
        self.check(action)?;
        match *action {
            Action::Grasp { hand, thing } => {
                self.support[thing] = None;
                self.covering[thing] = None;
                self.hands[hand.index()] = Some(thing);
            }
            Action::Place {
                hand,
                relation,
                target,
            } => {
                let held = self.hands[hand.index()].take();
                if let Some(held) = held {
                    self.support[held] = Some((relation, target));
                }
            }
            Action::Cover { hand, target } => {
                if let Some(cloth) = self.hands[hand.index()].take() {
                    self.covering[cloth] = Some(target);
                }
            }
            Action::Open { thing } => self.open[thing] = true,
            Action::Close { thing } => self.open[thing] = false,
            Action::ToggleOn { thing } => self.on[thing] = true,
            Action::ToggleOff { thing } => self.on[thing] = false,
            Action::Slice { thing, .. } => {
                let support = self.support[thing].take();
                self.present[thing] = false;
                for half in halves_of(thing).unwrap_or_default() {
                    self.present[half] = true;
                    self.support[half] = support;
                }
            }
            Action::Pour { target, .. } => self.water[target] = true,
            Action::Cook { thing } => self.cooked[thing] = true,
        }
        Ok(())
    }

    /// Every action possible now on the things of `room`, in a fixed order.
    pub fn possible_actions(&self, room: Room) -> Vec<Action> {
        let in_room: Vec<ThingId> = (0..CATALOGUE.len())
            .filter(|&t| CATALOGUE[t].room == room && self.present[t])
            .collect();
        let mut all = Vec::new();
        for hand in Hand::BOTH {
            for &thing in &in_room {
                all.push(Action::Grasp { hand, thing });
                all.push(Action::Cover {
                    hand,
                    target: thing,
                });
                all.push(Action::Slice { hand, thing });
                all.push(Action::Pour {
                    hand,
                    target: thing,
                });
                for relation in [Relation::OnTop, Relation::Inside, Relation::Under] {
                    all.push(Action::Place {
                        hand,
                        relation,
                        target: thing,
                    });
                }
            }
        }
        for &thing in &in_room {
            all.extend([
                Action::Open { thing },
                Action::Close { thing },
                Action::ToggleOn { thing },
                Action::ToggleOff { thing },
                Action::Cook { thing },
            ]);
        }
        all.retain(|a| self.check(a).is_ok());
        all
    }

    /// The scene graph of this state; every node's visibility is left empty.
    pub fn scene_graph(&self) -> SceneGraph {
        let node = |name: &str, category: &str, states: Vec<String>| SceneNode {
            name: name.to_string(),
            category: Some(category.to_string()),
            states,
            visibility: Default::default(),
            parent: None,
        };
        let mut nodes = vec![node(ROBOT, "agent", vec![])];
        for (t, thing) in CATALOGUE.iter().enumerate() {
            if !self.present[t] {
                continue;
            }
            let mut states = Vec::new();
            if self.open[t] {
                states.push("Open".to_string());
            }
            if self.on[t] {
                states.push("ToggledOn".to_string());
            }
            if self.cooked[t] {
                states.push("Cooked".to_string());
            }
            let mut n = node(thing.name, thing.category, states);
            if t == things::HALF_APPLE_0 || t == things::HALF_APPLE_1 {
                n.parent = Some(vec![CATALOGUE[APPLE].name.to_string()]);
            }
            nodes.push(n);
        }
        let edge = |from: &str, to: &str, state: &str| SceneEdge {
            from: from.to_string(),
            to: to.to_string(),
            states: vec![state.to_string()],
        };
        let mut edges = Vec::new();
        for hand in Hand::BOTH {
            if let Some(t) = self.held(hand) {
                edges.push(edge(ROBOT, CATALOGUE[t].name, hand.grasping_state()));
            }
        }
        for (t, thing) in CATALOGUE.iter().enumerate() {
            if !self.present[t] {
                continue;
            }
            if let Some((relation, target)) = self.support[t] {
                edges.push(edge(thing.name, CATALOGUE[target].name, relation.state()));
            }
            if let Some(target) = self.covering[t] {
                edges.push(edge(CATALOGUE[target].name, thing.name, "Covered"));
            }
            if self.water[t] {
                edges.push(edge(thing.name, CATALOGUE[WATER].name, "Contains"));
            }
        }
        SceneGraph { nodes, edges }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::things::*;

    #[test]
    fn grasping_and_placing_move_the_support_edge() {
        let mut s = WorldState::initial();
        s.apply(&Action::Grasp {
            hand: Hand::Left,
            thing: BOWL,
        })
        .unwrap();
        assert_eq!(s.held(Hand::Left), Some(BOWL));
        assert_eq!(s.support(BOWL), None);
        let err = s
            .apply(&Action::Place {
                hand: Hand::Left,
                relation: Relation::Inside,
                target: CABINET,
            })
            .unwrap_err();
        assert!(err.contains("cannot go Inside"), "{err}");
        s.apply(&Action::Open { thing: CABINET }).unwrap();
        s.apply(&Action::Place {
            hand: Hand::Left,
            relation: Relation::Inside,
            target: CABINET,
        })
        .unwrap();
        let g = s.scene_graph();
        assert!(
            g.edges
                .iter()
                .any(|e| e.from == "bowl_0" && e.to == "top_cabinet_0" && e.states == ["Inside"])
        );
        assert!(
            g.nodes
                .iter()
                .any(|n| n.name == "top_cabinet_0" && n.states == ["Open"])
        );
    }

    #[test]
    fn slicing_replaces_the_apple_by_its_halves() {
        let mut s = WorldState::initial();
        let slice = Action::Slice {
            hand: Hand::Right,
            thing: APPLE,
        };
        assert!(s.check(&slice).is_err());
        s.apply(&Action::Grasp {
            hand: Hand::Right,
            thing: KNIFE,
        })
        .unwrap();
        s.apply(&slice).unwrap();
        let g = s.scene_graph();
        assert!(!g.nodes.iter().any(|n| n.name == "apple_0"));
        let halves: Vec<&SceneNode> = g
            .nodes
            .iter()
            .filter(|n| n.name.starts_with("half_apple"))
            .collect();
        assert_eq!(halves.len(), 2);
        assert!(
            halves
                .iter()
                .all(|n| n.parent == Some(vec!["apple_0".into()]))
        );
    }

    #[test]
    fn things_shut_away_or_covered_cannot_be_grasped() {
        let mut s = WorldState::initial();
        assert!(
            s.check(&Action::Grasp {
                hand: Hand::Left,
                thing: MUG
            })
            .is_err()
        );
        s.apply(&Action::Grasp {
            hand: Hand::Left,
            thing: DISHTOWEL,
        })
        .unwrap();
        s.apply(&Action::Cover {
            hand: Hand::Left,
            target: BOWL,
        })
        .unwrap();
        assert!(
            s.check(&Action::Grasp {
                hand: Hand::Right,
                thing: BOWL
            })
            .is_err()
        );
        assert_eq!(s.covered_by(BOWL), Some(DISHTOWEL));
        assert!(
            s.possible_actions(Room::Kitchen)
                .iter()
                .all(|a| s.check(a).is_ok())
        );
    }
}
