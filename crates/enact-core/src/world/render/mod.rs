//! What the robot's head camera sees: a pinhole camera (field of view, height, pitch towards
//! the room's work area), simple flat-shaded drawings of the room painted far to near, and
//! per-object pixel counts taken from the painted owner of every pixel, so an object hidden
//! behind a closed door or outside the frame has no visibility.
//!
//! - [`primitives`]: the canvas and its owner buffer, and the shapes painted on it.
//! - [`layout`]: the camera, where each object stands and in which order it is painted.
//! - [`painters`]: the arms and one drawing per look.

mod layout;
mod painters;
mod primitives;

use std::collections::BTreeMap;

use image::RgbImage;

use crate::scene_graph::record::Visibility;
use crate::world::state::WorldState;
use crate::world::things::{CATALOGUE, Look, Room, ThingId};
use layout::{Anchor, Camera, Scene};
use painters::{draw_arms, draw_thing};
use primitives::{Canvas, ROBOT_OWNER};

/// The camera sensor whose visibility ENACT reads.
pub const SENSOR: &str = "external_sensor1";

/// How frames are drawn: the rendering variants of an ablation dataset.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CameraRig {
    /// Horizontal (and vertical: frames are square) field of view, in degrees.
    pub fov_deg: f32,
    /// Height of the head camera above the floor, in metres.
    pub height_m: f32,
    /// Colour of the robot's arms.
    pub robot_colour: [u8; 3],
    /// Width and height of a frame, in pixels.
    pub image_size: u32,
}

impl Default for CameraRig {
    fn default() -> Self {
        CameraRig {
            fov_deg: 60.0,
            height_m: 1.6,
            robot_colour: [96, 104, 124],
            image_size: 512,
        }
    }
}

/// Parses a robot colour: a name (grey, white, black, red, green, blue, yellow, orange,
/// purple, skin) or `#rrggbb`.
pub fn parse_colour(text: &str) -> Result<[u8; 3], String> {
    let named = match text.to_ascii_lowercase().as_str() {
        "grey" | "gray" => Some([96, 104, 124]),
        "white" => Some([236, 236, 236]),
        "black" => Some([28, 28, 30]),
        "red" => Some([200, 40, 40]),
        "green" => Some([40, 150, 60]),
        "blue" => Some([40, 80, 200]),
        "yellow" => Some([230, 200, 40]),
        "orange" => Some([235, 130, 30]),
        "purple" => Some([130, 60, 170]),
        "skin" => Some([224, 172, 140]),
        _ => None,
    };
    if let Some(c) = named {
        return Ok(c);
    }
    let hex = text.strip_prefix('#').filter(|h| h.len() == 6);
    match hex.map(hex::decode) {
        Some(Ok(bytes)) => Ok([bytes[0], bytes[1], bytes[2]]),
        _ => Err(format!(
            "robot colour {text:?} is neither a known name (grey, white, black, red, green, \
             blue, yellow, orange, purple, skin) nor #rrggbb"
        )),
    }
}

/// A frame and what each object shows of itself in it.
#[derive(Debug, Clone)]
pub struct View {
    pub image: RgbImage,
    /// Node name -> visibility reading (absent when nothing of it is drawn).
    pub visibility: BTreeMap<String, Visibility>,
}

/// Draws the room as `state` has it and measures every object's visible pixels.
pub fn render(state: &WorldState, room: Room, rig: &CameraRig) -> View {
    let camera = Camera::new(rig, room);
    let scene = Scene {
        state,
        camera,
        room,
    };
    let (wall, floor) = match room {
        Room::Kitchen => ([226, 220, 200], [150, 140, 128]),
        Room::LivingRoom => ([200, 214, 226], [160, 120, 84]),
    };
    let mut canvas = Canvas::new(rig.image_size, wall);
    let back = 3.4;
    let floor_pts: Vec<(f32, f32)> = [
        [-8.0, 0.0, 0.3],
        [8.0, 0.0, 0.3],
        [8.0, 0.0, back],
        [-8.0, 0.0, back],
    ]
    .iter()
    .filter_map(|p| scene.camera.project(*p).map(|(u, v, _)| (u, v)))
    .collect();
    canvas.polygon(&floor_pts, floor, 0);

    let mut order: Vec<(f32, ThingId, Anchor)> = (0..CATALOGUE.len())
        .filter_map(|t| scene.anchor(t, 0).map(|a| (a.key, t, a)))
        .collect();
    // A cabinet is painted twice: its body behind its contents, its door in front of them.
    let doors: Vec<(f32, ThingId, Anchor)> = order
        .iter()
        .filter(|(_, t, _)| CATALOGUE[*t].look == Look::Cabinet)
        .filter_map(|&(_, t, a)| {
            let z = CATALOGUE[t].at?[2] - 0.01;
            Some((z, t, Anchor { key: z, ..a }))
        })
        .collect();
    order.extend(doors);
    // Far to near; ties keep catalogue order.
    order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    let mut arms_drawn = false;
    for (key, thing, anchor) in order {
        if key < 0.0 && !arms_drawn {
            draw_arms(&mut canvas, &scene.camera, rig);
            arms_drawn = true;
        }
        draw_thing(&mut canvas, &scene, thing, anchor);
    }
    if !arms_drawn {
        draw_arms(&mut canvas, &scene.camera, rig);
    }

    let size = rig.image_size as u64;
    let mut visibility = BTreeMap::new();
    for (owner, [count, x0, y0, x1, y1]) in canvas.visibility() {
        let name = if owner == ROBOT_OWNER {
            crate::world::state::ROBOT
        } else {
            CATALOGUE[(owner - 2) as usize].name
        };
        let reading = [
            count as u64,
            x0 as u64,
            y0 as u64,
            x1 as u64,
            y1 as u64,
            size,
            size,
        ]
        .iter()
        .map(|&v| v.into())
        .collect();
        let mut v = Visibility::new();
        v.insert(SENSOR.to_string(), reading);
        visibility.insert(name.to_string(), v);
    }
    View {
        image: canvas.image,
        visibility,
    }
}
