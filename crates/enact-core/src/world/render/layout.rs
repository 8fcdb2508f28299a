//! Where things are: the head camera's pinhole projection, each object's anchor in the room
//! (on a surface slot, inside, under, held, draped) and its place in the painting order, and
//! where a movable thing lands on screen.

use crate::world::render::CameraRig;
use crate::world::state::{Hand, Relation, WorldState};
use crate::world::things::{self, CATALOGUE, Look, Room, ThingId};

/// The robot's head camera: pitched down towards the room's work area.
pub(super) struct Camera {
    pub(super) eye: [f32; 3],
    /// Downward pitch, radians.
    pitch: f32,
    focal: f32,
    size: f32,
}

impl Camera {
    pub(super) fn new(rig: &CameraRig, room: Room) -> Camera {
        let target = match room {
            Room::Kitchen => [-0.25, 0.95, 2.7],
            Room::LivingRoom => [-0.15, 0.45, 2.5],
        };
        let eye = [target[0], rig.height_m, 0.0];
        let pitch = (rig.height_m - target[1]).atan2(target[2]);
        let size = rig.image_size as f32;
        let half_fov = (rig.fov_deg.clamp(5.0, 170.0) / 2.0).to_radians();
        Camera {
            eye,
            pitch,
            focal: size / 2.0 / half_fov.tan(),
            size,
        }
    }

    /// Camera-space coordinates (right, up, forward) of a world point.
    fn to_camera(&self, p: [f32; 3]) -> [f32; 3] {
        let d = [p[0] - self.eye[0], p[1] - self.eye[1], p[2] - self.eye[2]];
        let (s, c) = self.pitch.sin_cos();
        [d[0], d[1] * c + d[2] * s, -d[1] * s + d[2] * c]
    }

    fn to_world(&self, q: [f32; 3]) -> [f32; 3] {
        let (s, c) = self.pitch.sin_cos();
        [
            self.eye[0] + q[0],
            self.eye[1] + q[1] * c - q[2] * s,
            self.eye[2] + q[1] * s + q[2] * c,
        ]
    }

    /// Screen position and pixels per metre at that point (None behind the camera).
    pub(super) fn project(&self, p: [f32; 3]) -> Option<(f32, f32, f32)> {
        let q = self.to_camera(p);
        if q[2] < 0.05 {
            return None;
        }
        let scale = self.focal / q[2];
        Some((
            self.size / 2.0 + q[0] * scale,
            self.size / 2.0 - q[1] * scale,
            scale,
        ))
    }

    /// Where a gripper's jaws are, in world coordinates.
    pub(super) fn gripper(&self, hand: Hand) -> [f32; 3] {
        let x = match hand {
            Hand::Left => -0.2,
            Hand::Right => 0.2,
        };
        self.to_world([x, -0.2, 0.75])
    }
}

/// Where an object is drawn: its bottom centre in the room, and its place in the painting
/// order (larger keys are painted first).
#[derive(Debug, Clone, Copy)]
pub(super) struct Anchor {
    pub(super) at: [f32; 3],
    pub(super) key: f32,
    pub(super) held: bool,
}

/// The slot a thing prefers on a surface. Things that start on the same surface have
/// different ones, so they keep their places while others come and go.
pub(super) fn home_slot(thing: ThingId) -> usize {
    use things::*;
    match thing {
        KETTLE | PAN | REMOTE | BASKET | HALF_APPLE_0 => 0,
        BOWL | BOOK | HALF_APPLE_1 => 1,
        BACON | MUG => 2,
        PLATE | BLANKET => 3,
        BOARD | APPLE => 4,
        KNIFE => 5,
        DISHTOWEL => 6,
        _ => 0,
    }
}

/// The state being drawn, seen through the camera, in one room.
pub(super) struct Scene<'a> {
    pub(super) state: &'a WorldState,
    pub(super) camera: Camera,
    pub(super) room: Room,
}

impl Scene<'_> {
    /// The slot of `thing` among the things resting the same way on the same support: its
    /// home slot when free, otherwise the next free one (homes are served first).
    pub(super) fn slot(
        &self,
        thing: ThingId,
        relation: Relation,
        support: ThingId,
        slots: usize,
    ) -> usize {
        let here: Vec<ThingId> = (0..CATALOGUE.len())
            .filter(|&t| {
                self.state.is_present(t) && self.state.support(t) == Some((relation, support))
            })
            .collect();
        let mut owner: Vec<Option<ThingId>> = vec![None; slots];
        let mut homeless = Vec::new();
        for &t in &here {
            let home = home_slot(t) % slots;
            if owner[home].is_none() {
                owner[home] = Some(t);
            } else {
                homeless.push(t);
            }
        }
        for t in homeless {
            let home = home_slot(t) % slots;
            if let Some(free) = (0..slots)
                .map(|k| (home + k) % slots)
                .find(|&s| owner[s].is_none())
            {
                owner[free] = Some(t);
            }
        }
        owner
            .iter()
            .position(|o| *o == Some(thing))
            .unwrap_or(home_slot(thing) % slots)
    }

    pub(super) fn anchor(&self, thing: ThingId, depth: usize) -> Option<Anchor> {
        let spec = &CATALOGUE[thing];
        if spec.room != self.room || !self.state.is_present(thing) || depth > CATALOGUE.len() {
            return None;
        }
        if let Some(at) = spec.at {
            return Some(Anchor {
                at,
                key: at[2] + spec.size[2],
                held: false,
            });
        }
        if let Some(hand) = self.state.holder(thing) {
            let g = self.camera.gripper(hand);
            return Some(Anchor {
                at: [g[0], g[1] - spec.size[1] / 2.0, g[2]],
                key: -1.0,
                held: true,
            });
        }
        if let Some(target) = self.state.covers(thing) {
            let under = self.anchor(target, depth + 1)?;
            // After the covered thing and everything resting on it.
            return Some(Anchor {
                key: under.key - 0.01,
                ..under
            });
        }
        let (relation, support) = self.state.support(thing)?;
        let base = self.anchor(support, depth + 1)?;
        let sup = &CATALOGUE[support];
        if let Some([x0, y0, z0]) = sup.at {
            let [w, h, d] = sup.size;
            let (slots, y, z, key) = match relation {
                Relation::OnTop => {
                    let top = if sup.look == Look::Sofa { 0.45 } else { h };
                    let z = if sup.look == Look::Sofa {
                        z0 + 0.25
                    } else {
                        z0 + d / 2.0
                    };
                    (
                        things::surface_slots(support).unwrap_or(1),
                        y0 + top,
                        z,
                        base.key - 0.001,
                    )
                }
                Relation::Inside => (3, y0 + 0.03, z0 + 0.15, z0 - 0.005),
                Relation::Under => (2, 0.0, z0 + d / 2.0, base.key + 0.0005),
            };
            let slot = self.slot(thing, relation, support, slots);
            let x = x0 + w * (slot as f32 + 0.5) / slots as f32;
            return Some(Anchor {
                at: [x, y, z],
                key,
                held: false,
            });
        }
        // On another object: side by side across its top.
        let slots = things::surface_slots(support).unwrap_or(1);
        let slot = self.slot(thing, relation, support, slots) as f32;
        let offset = (slot - (slots as f32 - 1.0) / 2.0) * sup.size[0] * 0.45;
        Some(Anchor {
            at: [base.at[0] + offset, base.at[1] + sup.size[1], base.at[2]],
            key: base.key - 0.001,
            held: base.held,
        })
    }
}

/// The screen rectangle of a vertical world rectangle at depth `z`: (left, top, right, bottom).
pub(super) fn project_rect(
    camera: &Camera,
    x0: f32,
    y0: f32,
    x1: f32,
    y1: f32,
    z: f32,
) -> Option<(f32, f32, f32, f32)> {
    let (a, b, _) = camera.project([x0, y1, z])?;
    let (c, d, _) = camera.project([x1, y0, z])?;
    Some((a, b, c, d))
}

/// Where a movable thing lands on screen: its anchor at (`u`, `v`), its width and height in
/// pixels, and whether a hand holds it.
#[derive(Clone, Copy)]
pub(super) struct OnScreen {
    pub(super) u: f32,
    pub(super) v: f32,
    pub(super) w: f32,
    pub(super) h: f32,
    pub(super) held: bool,
}

impl OnScreen {
    /// The front of an upright thing: from the ground line up to its height plus `top` (the
    /// part of its top face the camera sees).
    pub(super) fn front(&self, top: f32) -> [(f32, f32); 4] {
        let Self { u, v, w, h, .. } = *self;
        [
            (u - w / 2.0, v - h - top),
            (u + w / 2.0, v - h - top),
            (u + w / 2.0, v),
            (u - w / 2.0, v),
        ]
    }
}

/// The screen box of a covered thing, where a cloth is draped.
pub(super) fn covered_box(scene: &Scene, target: ThingId) -> Option<(f32, f32, f32, f32)> {
    let spec = &CATALOGUE[target];
    let cam = &scene.camera;
    if let Some(at) = spec.at {
        let [w, h, _] = spec.size;
        let top = if spec.look == Look::Sofa { 0.85 } else { h };
        return project_rect(cam, at[0], at[1], at[0] + w, at[1] + top, at[2]);
    }
    let anchor = scene.anchor(target, 0)?;
    let (u, v, s) = cam.project(anchor.at)?;
    let [w, h, _] = spec.size;
    // Tall enough to hide what rests on a flat thing, such as food on a plate.
    let h = h.max(0.1);
    Some((u - w * s / 2.0, v - h * s * 1.2, u + w * s / 2.0, v))
}
