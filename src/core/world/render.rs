//! What the robot's head camera sees: a pinhole camera (field of view, height, pitch towards
//! the room's work area), simple flat-shaded drawings of the room painted far to near, and
//! per-object pixel counts taken from the painted owner of every pixel, so an object hidden
//! behind a closed door or outside the frame has no visibility.

use std::collections::BTreeMap;

use image::{Rgb, RgbImage};

use crate::core::scene_graph::record::Visibility;
use crate::core::world::state::{Hand, Relation, WorldState};
use crate::core::world::things::{self, CATALOGUE, Look, Room, Thing, ThingId};

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

struct Camera {
    eye: [f32; 3],
    /// Downward pitch, radians.
    pitch: f32,
    focal: f32,
    size: f32,
}

impl Camera {
    fn new(rig: &CameraRig, room: Room) -> Camera {
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
    fn project(&self, p: [f32; 3]) -> Option<(f32, f32, f32)> {
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
    fn gripper(&self, hand: Hand) -> [f32; 3] {
        let x = match hand {
            Hand::Left => -0.2,
            Hand::Right => 0.2,
        };
        self.to_world([x, -0.2, 0.75])
    }
}

/// Owner ids in the owner buffer: 0 nothing, 1 the robot, 2 + thing id.
const ROBOT_OWNER: u16 = 1;

fn owner_of(thing: ThingId) -> u16 {
    thing as u16 + 2
}

struct Canvas {
    image: RgbImage,
    owners: Vec<u16>,
    size: u32,
}

fn shade(c: [u8; 3], factor: f32) -> [u8; 3] {
    c.map(|v| (v as f32 * factor).clamp(0.0, 255.0) as u8)
}

impl Canvas {
    fn new(size: u32, background: [u8; 3]) -> Canvas {
        Canvas {
            image: RgbImage::from_pixel(size, size, Rgb(background)),
            owners: vec![0; (size * size) as usize],
            size,
        }
    }

    /// Paints pixels `x0..=x1` of row `y` (already clipped to the canvas).
    fn span(&mut self, y: u32, x0: u32, x1: u32, colour: [u8; 3], owner: u16) {
        let row = (y * self.size) as usize;
        let pixels: &mut [u8] = &mut self.image;
        for x in x0 as usize..=x1 as usize {
            pixels[(row + x) * 3..(row + x) * 3 + 3].copy_from_slice(&colour);
        }
        self.owners[row + x0 as usize..=row + x1 as usize].fill(owner);
    }

    /// Paints the pixels of row `y` whose centres lie in `[left, right]`.
    fn fill_row(&mut self, y: u32, left: f32, right: f32, colour: [u8; 3], owner: u16) {
        let max = self.size as f32 - 1.0;
        let first = (left - 0.5).ceil().max(0.0);
        let last = (right - 0.5).floor().min(max);
        if first <= last {
            self.span(y, first as u32, last as u32, colour, owner);
        }
    }

    /// Pixel rows a shape spanning `y0..y1` may touch.
    fn rows(&self, y0: f32, y1: f32) -> Option<(u32, u32)> {
        if !(y0.is_finite() && y1.is_finite()) {
            return None;
        }
        let max = self.size as f32 - 1.0;
        let (a, b) = (y0.floor().max(0.0), y1.ceil().min(max));
        (a <= b).then_some((a as u32, b as u32))
    }

    /// Fills a convex polygon, row by row, sampling pixel centres.
    fn polygon(&mut self, pts: &[(f32, f32)], colour: [u8; 3], owner: u16) {
        if pts.len() < 3 || pts.iter().any(|p| !(p.0.is_finite() && p.1.is_finite())) {
            return;
        }
        let y0 = pts.iter().map(|p| p.1).fold(f32::MAX, f32::min);
        let y1 = pts.iter().map(|p| p.1).fold(f32::MIN, f32::max);
        let Some((first, last)) = self.rows(y0, y1) else {
            return;
        };
        for y in first..=last {
            let py = y as f32 + 0.5;
            let (mut left, mut right) = (f32::MAX, f32::MIN);
            for i in 0..pts.len() {
                let (p, q) = (pts[i], pts[(i + 1) % pts.len()]);
                if !((p.1 <= py && py <= q.1) || (q.1 <= py && py <= p.1)) {
                    continue;
                }
                if (q.1 - p.1).abs() < 1e-6 {
                    left = left.min(p.0.min(q.0));
                    right = right.max(p.0.max(q.0));
                } else {
                    let x = p.0 + (py - p.1) / (q.1 - p.1) * (q.0 - p.0);
                    left = left.min(x);
                    right = right.max(x);
                }
            }
            if left <= right {
                self.fill_row(y, left, right, colour, owner);
            }
        }
    }

    fn rect(&mut self, x0: f32, y0: f32, x1: f32, y1: f32, colour: [u8; 3], owner: u16) {
        self.polygon(&[(x0, y0), (x1, y0), (x1, y1), (x0, y1)], colour, owner);
    }

    /// Fills an axis-aligned ellipse.
    fn ellipse(&mut self, cx: f32, cy: f32, rx: f32, ry: f32, colour: [u8; 3], owner: u16) {
        if !(rx > 0.0 && ry > 0.0 && cx.is_finite()) {
            return;
        }
        let Some((first, last)) = self.rows(cy - ry, cy + ry) else {
            return;
        };
        for y in first..=last {
            let dy = (y as f32 + 0.5 - cy) / ry;
            if dy.abs() <= 1.0 {
                let half = rx * (1.0 - dy * dy).sqrt();
                self.fill_row(y, cx - half, cx + half, colour, owner);
            }
        }
    }

    /// The lower half of an ellipse (a bowl's body).
    fn lower_half_ellipse(&mut self, cx: f32, cy: f32, rx: f32, ry: f32, c: [u8; 3], o: u16) {
        let pts: Vec<(f32, f32)> = (0..=16)
            .map(|i| {
                let t = std::f32::consts::PI * i as f32 / 16.0;
                (cx + rx * t.cos(), cy + ry * t.sin())
            })
            .collect();
        self.polygon(&pts, c, o);
    }

    /// A thick line as a quadrilateral.
    fn line(&mut self, a: (f32, f32), b: (f32, f32), width: f32, colour: [u8; 3], owner: u16) {
        let (dx, dy) = (b.0 - a.0, b.1 - a.1);
        let len = (dx * dx + dy * dy).sqrt().max(1e-3);
        let (nx, ny) = (-dy / len * width / 2.0, dx / len * width / 2.0);
        self.polygon(
            &[
                (a.0 + nx, a.1 + ny),
                (b.0 + nx, b.1 + ny),
                (b.0 - nx, b.1 - ny),
                (a.0 - nx, a.1 - ny),
            ],
            colour,
            owner,
        );
    }

    fn visibility(&self) -> BTreeMap<u16, [u32; 5]> {
        let mut seen: BTreeMap<u16, [u32; 5]> = BTreeMap::new();
        for (i, &owner) in self.owners.iter().enumerate() {
            if owner == 0 {
                continue;
            }
            let (x, y) = (i as u32 % self.size, i as u32 / self.size);
            let e = seen.entry(owner).or_insert([0, x, y, x, y]);
            e[0] += 1;
            e[1] = e[1].min(x);
            e[2] = e[2].min(y);
            e[3] = e[3].max(x);
            e[4] = e[4].max(y);
        }
        seen
    }
}

/// Where an object is drawn: its bottom centre in the room, and its place in the painting
/// order (larger keys are painted first).
#[derive(Debug, Clone, Copy)]
struct Anchor {
    at: [f32; 3],
    key: f32,
    held: bool,
}

/// The slot a thing prefers on a surface. Things that start on the same surface have
/// different ones, so they keep their places while others come and go.
fn home_slot(thing: ThingId) -> usize {
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

struct Scene<'a> {
    state: &'a WorldState,
    camera: Camera,
    room: Room,
}

impl Scene<'_> {
    /// The slot of `thing` among the things resting the same way on the same support: its
    /// home slot when free, otherwise the next free one (homes are served first).
    fn slot(&self, thing: ThingId, relation: Relation, support: ThingId, slots: usize) -> usize {
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

    fn anchor(&self, thing: ThingId, depth: usize) -> Option<Anchor> {
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
            crate::core::world::state::ROBOT
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

fn draw_arms(canvas: &mut Canvas, camera: &Camera, rig: &CameraRig) {
    let s = rig.image_size as f32;
    for hand in Hand::BOTH {
        let Some((gx, gy, _)) = camera.project(camera.gripper(hand)) else {
            continue;
        };
        let shoulder = match hand {
            Hand::Left => (s * 0.06, s * 1.02),
            Hand::Right => (s * 0.94, s * 1.02),
        };
        let elbow = ((shoulder.0 + gx) / 2.0, gy + s * 0.12);
        canvas.line(shoulder, elbow, s * 0.1, rig.robot_colour, ROBOT_OWNER);
        canvas.ellipse(
            elbow.0,
            elbow.1,
            s * 0.055,
            s * 0.055,
            shade(rig.robot_colour, 0.8),
            ROBOT_OWNER,
        );
        canvas.line(
            elbow,
            (gx, gy + s * 0.05),
            s * 0.075,
            rig.robot_colour,
            ROBOT_OWNER,
        );
        let jaw = [50, 52, 58];
        canvas.rect(
            gx - s * 0.06,
            gy + s * 0.03,
            gx + s * 0.06,
            gy + s * 0.065,
            jaw,
            ROBOT_OWNER,
        );
        canvas.rect(
            gx - s * 0.06,
            gy - s * 0.04,
            gx - s * 0.04,
            gy + s * 0.05,
            jaw,
            ROBOT_OWNER,
        );
        canvas.rect(
            gx + s * 0.04,
            gy - s * 0.04,
            gx + s * 0.06,
            gy + s * 0.05,
            jaw,
            ROBOT_OWNER,
        );
    }
}

/// Draws an axis-aligned box: visible side, top or bottom, then the front face.
fn draw_box(
    canvas: &mut Canvas,
    camera: &Camera,
    at: [f32; 3],
    size: [f32; 3],
    colour: [u8; 3],
    owner: u16,
) {
    let [x0, y0, z0] = at;
    let (x1, y1, z1) = (x0 + size[0], y0 + size[1], z0 + size[2]);
    let quad = |c: &mut Canvas, pts: [[f32; 3]; 4], col: [u8; 3]| {
        let pts: Vec<(f32, f32)> = pts
            .iter()
            .filter_map(|p| camera.project(*p).map(|(u, v, _)| (u, v)))
            .collect();
        if pts.len() == 4 {
            c.polygon(&pts, col, owner);
        }
    };
    if x1 < camera.eye[0] {
        quad(
            canvas,
            [[x1, y0, z0], [x1, y0, z1], [x1, y1, z1], [x1, y1, z0]],
            shade(colour, 0.7),
        );
    }
    if x0 > camera.eye[0] {
        quad(
            canvas,
            [[x0, y0, z0], [x0, y0, z1], [x0, y1, z1], [x0, y1, z0]],
            shade(colour, 0.7),
        );
    }
    if y1 < camera.eye[1] {
        quad(
            canvas,
            [[x0, y1, z0], [x1, y1, z0], [x1, y1, z1], [x0, y1, z1]],
            shade(colour, 1.12),
        );
    } else if y0 > camera.eye[1] {
        quad(
            canvas,
            [[x0, y0, z0], [x1, y0, z0], [x1, y0, z1], [x0, y0, z1]],
            shade(colour, 0.6),
        );
    }
    quad(
        canvas,
        [[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0]],
        colour,
    );
}

fn project_rect(
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

fn draw_thing(canvas: &mut Canvas, scene: &Scene, thing: ThingId, anchor: Anchor) {
    let spec = &CATALOGUE[thing];
    let p = Paint {
        scene,
        thing,
        spec,
        owner: owner_of(thing),
        col: spec.colour,
        dark: shade(spec.colour, 0.55),
        water: owner_of(things::WATER),
        water_colour: CATALOGUE[things::WATER].colour,
    };
    if let Some(at) = spec.at {
        match spec.look {
            Look::Counter => draw_counter(canvas, &p, at),
            Look::Cabinet => draw_cabinet(canvas, &p, at, anchor),
            Look::Stove => draw_stove(canvas, &p, at),
            Look::Sofa => draw_sofa(canvas, &p, at),
            Look::CoffeeTable => draw_coffee_table(canvas, &p, at),
            Look::Lamp => draw_lamp(canvas, &p, at),
            _ => draw_box(canvas, &scene.camera, at, spec.size, p.col, p.owner),
        }
        return;
    }
    let Some((u, v, mut s)) = scene.camera.project(anchor.at) else {
        return;
    };
    let [w0, h0, _] = spec.size;
    if anchor.held {
        // Carried things are drawn at a legible size rather than their true one up close.
        s = s.min(canvas.size as f32 * 0.3 / w0.max(0.05));
    }
    let at = OnScreen {
        u,
        v,
        w: w0 * s,
        h: h0 * s,
        held: anchor.held,
    };
    match spec.look {
        Look::Plate => draw_plate(canvas, &p, &at),
        Look::Bowl => draw_bowl(canvas, &p, &at),
        Look::Mug => draw_mug(canvas, &p, &at),
        Look::Apple => draw_apple(canvas, &p, &at),
        Look::HalfApple => draw_half_apple(canvas, &p, &at),
        Look::Board => draw_board(canvas, &p, &at),
        Look::Knife => draw_knife(canvas, &p, &at),
        Look::Pan => draw_pan(canvas, &p, &at),
        Look::Bacon => draw_bacon(canvas, &p, &at),
        Look::Kettle => draw_kettle(canvas, &p, &at),
        Look::Cloth => draw_cloth(canvas, &p, &at),
        Look::Book => draw_book(canvas, &p, &at),
        Look::Remote => draw_remote(canvas, &p, &at),
        Look::Basket => draw_basket(canvas, &p, &at),
        _ => {}
    }
}

/// What every drawing of one thing shares: the scene, the thing, its catalogue entry, the
/// owner id its pixels are marked with, and its colours (water's too, for things that hold it).
struct Paint<'a> {
    scene: &'a Scene<'a>,
    thing: ThingId,
    spec: &'static Thing,
    owner: u16,
    col: [u8; 3],
    dark: [u8; 3],
    water: u16,
    water_colour: [u8; 3],
}

/// Where a movable thing lands on screen: its anchor at (`u`, `v`), its width and height in
/// pixels, and whether a hand holds it.
#[derive(Clone, Copy)]
struct OnScreen {
    u: f32,
    v: f32,
    w: f32,
    h: f32,
    held: bool,
}

impl OnScreen {
    /// The front of an upright thing: from the ground line up to its height plus `top` (the
    /// part of its top face the camera sees).
    fn front(&self, top: f32) -> [(f32, f32); 4] {
        let Self { u, v, w, h, .. } = *self;
        [
            (u - w / 2.0, v - h - top),
            (u + w / 2.0, v - h - top),
            (u + w / 2.0, v),
            (u - w / 2.0, v),
        ]
    }
}

/// Fills `pts` with a darker rim 1.5 px wide, so small things stand out from what is behind.
fn outline(owner: u16, c: &mut Canvas, pts: &[(f32, f32)], fill: [u8; 3]) {
    let cx = pts.iter().map(|p| p.0).sum::<f32>() / pts.len() as f32;
    let cy = pts.iter().map(|p| p.1).sum::<f32>() / pts.len() as f32;
    let grown: Vec<(f32, f32)> = pts
        .iter()
        .map(|&(x, y)| {
            let (dx, dy) = (x - cx, y - cy);
            let n = (dx * dx + dy * dy).sqrt().max(1e-3);
            (x + dx / n * 1.5, y + dy / n * 1.5)
        })
        .collect();
    c.polygon(&grown, shade(fill, 0.45), owner);
    c.polygon(pts, fill, owner);
}

fn draw_counter(canvas: &mut Canvas, p: &Paint<'_>, at: [f32; 3]) {
    let cam = &p.scene.camera;
    let [w, _, _] = p.spec.size;
    let spec = p.spec;
    let owner = p.owner;
    let col = p.col;
    let dark = p.dark;
    draw_box(canvas, cam, at, spec.size, col, owner);
    for i in 0..4 {
        let x = at[0] + w * (i as f32 + 0.5) / 4.0;
        if let Some((u0, v0, u1, v1)) =
            project_rect(cam, x - 0.2, at[1] + 0.1, x + 0.2, at[1] + 0.75, at[2])
        {
            canvas.rect(u0, v0, u1, v1, shade(col, 0.92), owner);
            canvas.rect(
                u0,
                v0 + (v1 - v0) * 0.1,
                u1,
                v0 + (v1 - v0) * 0.14,
                dark,
                owner,
            );
        }
    }
}

fn draw_cabinet(canvas: &mut Canvas, p: &Paint<'_>, at: [f32; 3], anchor: Anchor) {
    let cam = &p.scene.camera;
    let state = p.scene.state;
    let [w, h, _] = p.spec.size;
    let spec = p.spec;
    let owner = p.owner;
    let col = p.col;
    let thing = p.thing;
    if anchor.key > at[2] {
        // The body first; the contents and then the door are painted later.
        draw_box(canvas, cam, at, spec.size, col, owner);
        if let Some((u0, v0, u1, v1)) = project_rect(
            cam,
            at[0] + 0.03,
            at[1] + 0.03,
            at[0] + w - 0.03,
            at[1] + h - 0.03,
            at[2],
        ) {
            canvas.rect(u0, v0, u1, v1, [60, 42, 30], owner);
            let mid = (v0 + v1) / 2.0;
            canvas.rect(u0, mid - 2.0, u1, mid + 2.0, shade(col, 0.8), owner);
        }
    } else if state.is_open(thing) {
        // Swung 100 degrees about the left hinge, towards the camera.
        let (dx, dz) = (w * -0.1736, -w * 0.9848);
        let pts: Vec<(f32, f32)> = [
            [at[0], at[1], at[2]],
            [at[0] + dx, at[1], at[2] + dz],
            [at[0] + dx, at[1] + h, at[2] + dz],
            [at[0], at[1] + h, at[2]],
        ]
        .iter()
        .filter_map(|p| cam.project(*p).map(|(u, v, _)| (u, v)))
        .collect();
        if pts.len() == 4 {
            canvas.polygon(&pts, shade(col, 0.85), owner);
        }
    } else if let Some((u0, v0, u1, v1)) =
        project_rect(cam, at[0], at[1], at[0] + w, at[1] + h, at[2])
    {
        canvas.rect(u0, v0, u1, v1, col, owner);
        canvas.rect(
            u0 + 3.0,
            v0 + 3.0,
            u1 - 3.0,
            v1 - 3.0,
            shade(col, 1.1),
            owner,
        );
        let knob = (u1 - (u1 - u0) * 0.1, (v0 + v1) / 2.0);
        canvas.ellipse(knob.0, knob.1, 4.0, 4.0, [230, 200, 120], owner);
    }
}

fn draw_stove(canvas: &mut Canvas, p: &Paint<'_>, at: [f32; 3]) {
    let cam = &p.scene.camera;
    let state = p.scene.state;
    let [w, h, d] = p.spec.size;
    let spec = p.spec;
    let owner = p.owner;
    let col = p.col;
    let thing = p.thing;
    draw_box(canvas, cam, at, spec.size, col, owner);
    let on = state.is_on(thing);
    for bx in [0.25f32, 0.75] {
        if let Some((u, v, s)) = cam.project([at[0] + w * bx, at[1] + h, at[2] + d * 0.5]) {
            let hot = on;
            canvas.ellipse(u, v, 0.14 * s, 0.05 * s, [30, 30, 30], owner);
            if hot {
                canvas.ellipse(u, v, 0.12 * s, 0.04 * s, [255, 70, 20], owner);
                canvas.ellipse(u, v, 0.06 * s, 0.02 * s, [255, 200, 60], owner);
            } else {
                canvas.ellipse(u, v, 0.09 * s, 0.03 * s, [70, 70, 72], owner);
            }
        }
    }
    if let Some((u0, v0, u1, v1)) = project_rect(
        cam,
        at[0] + 0.08,
        at[1] + 0.1,
        at[0] + w - 0.08,
        at[1] + 0.6,
        at[2],
    ) {
        // A switched-on stove shows it across its whole front: the oven window glows.
        let window = if on { [255, 130, 40] } else { [40, 40, 46] };
        canvas.rect(u0, v0, u1, v1, window, owner);
    }
    for k in 0..3 {
        if let Some((u, v, s)) =
            cam.project([at[0] + w * (0.25 + 0.25 * k as f32), at[1] + 0.78, at[2]])
        {
            let knob = if on && k == 0 {
                [255, 90, 30]
            } else {
                [60, 60, 60]
            };
            canvas.ellipse(u, v, 0.035 * s, 0.035 * s, knob, owner);
        }
    }
}

fn draw_sofa(canvas: &mut Canvas, p: &Paint<'_>, at: [f32; 3]) {
    let cam = &p.scene.camera;
    let [w, h, d] = p.spec.size;
    let owner = p.owner;
    let col = p.col;
    draw_box(
        canvas,
        cam,
        [at[0], at[1] + 0.45, at[2] + d - 0.2],
        [w, h - 0.45, 0.2],
        shade(col, 0.9),
        owner,
    );
    draw_box(canvas, cam, at, [w, 0.45, d], col, owner);
    draw_box(
        canvas,
        cam,
        [at[0] - 0.12, at[1], at[2]],
        [0.12, 0.62, d],
        shade(col, 0.8),
        owner,
    );
    draw_box(
        canvas,
        cam,
        [at[0] + w, at[1], at[2]],
        [0.12, 0.62, d],
        shade(col, 0.8),
        owner,
    );
}

fn draw_coffee_table(canvas: &mut Canvas, p: &Paint<'_>, at: [f32; 3]) {
    let cam = &p.scene.camera;
    let [w, h, d] = p.spec.size;
    let owner = p.owner;
    let col = p.col;
    let dark = p.dark;
    for (lx, lz) in [
        (0.05, 0.05),
        (w - 0.1, 0.05),
        (0.05, d - 0.1),
        (w - 0.1, d - 0.1),
    ] {
        draw_box(
            canvas,
            cam,
            [at[0] + lx, 0.0, at[2] + lz],
            [0.05, h - 0.05, 0.05],
            dark,
            owner,
        );
    }
    draw_box(
        canvas,
        cam,
        [at[0], h - 0.06, at[2]],
        [w, 0.06, d],
        col,
        owner,
    );
}

fn draw_lamp(canvas: &mut Canvas, p: &Paint<'_>, at: [f32; 3]) {
    let cam = &p.scene.camera;
    let state = p.scene.state;
    let [w, h, d] = p.spec.size;
    let owner = p.owner;
    let dark = p.dark;
    let thing = p.thing;
    let cx = at[0] + w / 2.0;
    let cz = at[2] + d / 2.0;
    let on = state.is_on(thing);
    if on && let Some((u, v, s)) = cam.project([cx, h - 0.12, cz]) {
        canvas.ellipse(u, v, 0.55 * s, 0.5 * s, [250, 240, 170], owner);
        canvas.ellipse(u, v, 0.38 * s, 0.34 * s, [255, 248, 200], owner);
    }
    if let Some((u, v, s)) = cam.project([cx, 0.0, cz]) {
        canvas.ellipse(u, v, 0.16 * s, 0.05 * s, dark, owner);
    }
    if let (Some(a), Some(b)) = (cam.project([cx, 0.0, cz]), cam.project([cx, h - 0.25, cz])) {
        canvas.line((a.0, a.1), (b.0, b.1), 0.035 * a.2, dark, owner);
    }
    if let (Some((u0, v0, s)), Some((_, v1, _))) =
        (cam.project([cx, h - 0.3, cz]), cam.project([cx, h, cz]))
    {
        let shade_colour = if on { [255, 226, 90] } else { [236, 228, 206] };
        canvas.polygon(
            &[
                (u0 - 0.2 * s, v0),
                (u0 + 0.2 * s, v0),
                (u0 + 0.12 * s, v1),
                (u0 - 0.12 * s, v1),
            ],
            shade_colour,
            owner,
        );
    }
}

fn draw_plate(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    let owner = p.owner;
    let col = p.col;
    canvas.ellipse(
        u,
        v - h / 2.0,
        w / 2.0 + 1.5,
        (w * 0.16).max(h) + 1.5,
        [120, 120, 120],
        owner,
    );
    canvas.ellipse(u, v - h / 2.0, w / 2.0, (w * 0.16).max(h), col, owner);
    canvas.ellipse(
        u,
        v - h / 2.0,
        w * 0.32,
        (w * 0.1).max(h * 0.6),
        [232, 232, 226],
        owner,
    );
}

fn draw_bowl(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let state = p.scene.state;
    let OnScreen { u, v, w, h, .. } = *at;
    let owner = p.owner;
    let col = p.col;
    let water = p.water;
    let water_colour = p.water_colour;
    let thing = p.thing;
    canvas.lower_half_ellipse(u, v - h, w / 2.0 + 1.5, h + 1.5, shade(col, 0.5), owner);
    canvas.lower_half_ellipse(u, v - h, w / 2.0, h, col, owner);
    canvas.ellipse(u, v - h, w / 2.0, w * 0.14, shade(col, 1.3), owner);
    if state.has_water(thing) {
        // Filled: water splashes up over the rim, then fills the bowl to the brim.
        for k in 0..6 {
            let k = k as f32;
            canvas.ellipse(
                u + (k - 2.5) * w * 0.17,
                v - h - w * (0.25 + 0.12 * (2.5 - (k - 2.5).abs())),
                w * 0.12,
                w * 0.12,
                water_colour,
                water,
            );
        }
        canvas.ellipse(u, v - h, w * 0.6, w * 0.2, [200, 228, 250], water);
        canvas.ellipse(u, v - h, w * 0.48, w * 0.13, water_colour, water);
        canvas.lower_half_ellipse(
            u,
            v - h,
            w * 0.44,
            h * 0.8,
            shade(water_colour, 0.85),
            water,
        );
        canvas.ellipse(
            u - w * 0.15,
            v - h,
            w * 0.12,
            w * 0.04,
            [235, 245, 255],
            water,
        );
    } else {
        canvas.ellipse(u, v - h, w * 0.42, w * 0.1, shade(col, 0.7), owner);
    }
}

fn draw_mug(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let state = p.scene.state;
    let OnScreen { u, v, w, h, .. } = *at;
    let owner = p.owner;
    let col = p.col;
    let water = p.water;
    let water_colour = p.water_colour;
    let thing = p.thing;
    canvas.ellipse(
        u + w * 0.55,
        v - h * 0.5,
        w * 0.28,
        h * 0.28,
        shade(col, 0.6),
        owner,
    );
    outline(owner, canvas, &at.front(0.0), col);
    let full = state.has_water(thing);
    let rim = if full {
        (water_colour, water)
    } else {
        ([80, 20, 20], owner)
    };
    canvas.ellipse(u, v - h, w / 2.0, w * 0.16, rim.0, rim.1);
    if full {
        // Steam over a filled mug: tea is visible at thumbnail size.
        for k in 0..5 {
            let k = k as f32;
            canvas.ellipse(
                u + (k % 2.0 - 0.5) * w * 0.5,
                v - h - w * (0.45 + 0.5 * k),
                w * 0.6,
                w * 0.36,
                [245, 245, 250],
                water,
            );
        }
    }
}

fn draw_apple(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, .. } = *at;
    let owner = p.owner;
    let col = p.col;
    canvas.ellipse(
        u,
        v - w / 2.0,
        w / 2.0 + 1.5,
        w / 2.0 + 1.5,
        [110, 10, 20],
        owner,
    );
    canvas.ellipse(u, v - w / 2.0, w / 2.0, w / 2.0, col, owner);
    canvas.line(
        (u, v - w),
        (u + w * 0.1, v - w * 1.25),
        w * 0.08,
        [90, 60, 30],
        owner,
    );
    canvas.ellipse(
        u + w * 0.22,
        v - w * 1.12,
        w * 0.16,
        w * 0.08,
        [60, 160, 60],
        owner,
    );
}

fn draw_half_apple(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    let owner = p.owner;
    let col = p.col;
    // Juice on the surface under a freshly cut half.
    canvas.ellipse(u, v, w * 0.95, w * 0.3, [240, 170, 170], owner);
    canvas.lower_half_ellipse(u, v - h, w / 2.0 + 1.5, h + 1.5, [110, 10, 20], owner);
    canvas.lower_half_ellipse(u, v - h, w / 2.0, h, col, owner);
    // The cut face, turned to the camera: pale flesh and the core.
    canvas.ellipse(u, v - h, w / 2.0, w * 0.34, [250, 240, 200], owner);
    canvas.ellipse(u, v - h, w * 0.1, w * 0.07, [120, 80, 40], owner);
}

fn draw_board(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    let owner = p.owner;
    let col = p.col;
    let top = w * 0.18;
    outline(owner, canvas, &at.front(top), col);
    canvas.rect(u - w / 2.0, v - h, u + w / 2.0, v, shade(col, 0.8), owner);
}

fn draw_knife(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    let owner = p.owner;
    let col = p.col;
    let blade = [
        (u - w / 2.0, v - h),
        (u + w * 0.1, v - h * 1.6),
        (u + w * 0.1, v),
        (u - w / 2.0, v),
    ];
    outline(owner, canvas, &blade, col);
    canvas.rect(
        u + w * 0.1,
        v - h * 1.2,
        u + w / 2.0,
        v,
        [40, 30, 25],
        owner,
    );
}

fn draw_pan(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    let owner = p.owner;
    let col = p.col;
    canvas.line(
        (u + w * 0.4, v - h),
        (u + w * 0.95, v - h * 1.4),
        h * 0.5 + 2.0,
        [30, 30, 30],
        owner,
    );
    canvas.ellipse(
        u,
        v - h / 2.0,
        w / 2.0 + 1.5,
        w * 0.17 + 1.5,
        [20, 20, 20],
        owner,
    );
    canvas.ellipse(u, v - h / 2.0, w / 2.0, w * 0.17, col, owner);
    canvas.ellipse(u, v - h / 2.0, w * 0.4, w * 0.12, shade(col, 1.4), owner);
}

fn draw_bacon(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let state = p.scene.state;
    let OnScreen { u, v, w, h, .. } = *at;
    let owner = p.owner;
    let col = p.col;
    let thing = p.thing;
    let c = if state.is_cooked(thing) {
        [150, 75, 35]
    } else {
        col
    };
    let fat = if state.is_cooked(thing) {
        [200, 150, 90]
    } else {
        [252, 225, 220]
    };
    if state.is_cooked(thing) {
        // Cooked bacon has curled and rendered its fat: a crisp dark halo around the strips
        // makes the change read at thumbnail size.
        canvas.ellipse(
            u,
            v - h * 1.6,
            w * 0.72,
            h * 3.2 + w * 0.12,
            [95, 50, 20],
            owner,
        );
        canvas.ellipse(
            u,
            v - h * 1.6,
            w * 0.62,
            h * 2.6 + w * 0.08,
            [185, 120, 55],
            owner,
        );
    }
    for k in 0..2 {
        let y = v - h * (1.0 + k as f32 * 1.3);
        outline(
            owner,
            canvas,
            &[
                (u - w / 2.0, y - h),
                (u + w / 2.0, y - h * 1.3),
                (u + w / 2.0, y),
                (u - w / 2.0, y + h * 0.3),
            ],
            c,
        );
        canvas.line(
            (u - w / 2.0, y - h * 0.4),
            (u + w / 2.0, y - h * 0.7),
            (h * 0.25).max(1.0),
            fat,
            owner,
        );
    }
}

fn draw_kettle(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let state = p.scene.state;
    let OnScreen { u, v, w, h, .. } = *at;
    let owner = p.owner;
    let col = p.col;
    let water = p.water;
    let water_colour = p.water_colour;
    let thing = p.thing;
    canvas.polygon(
        &[
            (u + w * 0.35, v - h * 0.5),
            (u + w * 0.75, v - h * 0.95),
            (u + w * 0.75, v - h * 0.85),
            (u + w * 0.35, v - h * 0.3),
        ],
        shade(col, 0.7),
        owner,
    );
    outline(
        owner,
        canvas,
        &[
            (u - w / 2.0, v),
            (u + w / 2.0, v),
            (u + w * 0.38, v - h * 0.85),
            (u - w * 0.38, v - h * 0.85),
        ],
        col,
    );
    canvas.line(
        (u - w * 0.3, v - h * 0.85),
        (u, v - h * 1.1),
        h * 0.07 + 1.0,
        [40, 40, 40],
        owner,
    );
    canvas.line(
        (u, v - h * 1.1),
        (u + w * 0.3, v - h * 0.85),
        h * 0.07 + 1.0,
        [40, 40, 40],
        owner,
    );
    let window = (u - w * 0.2, v - h * 0.7, u + w * 0.1, v - h * 0.1);
    canvas.rect(
        window.0,
        window.1,
        window.2,
        window.3,
        [230, 240, 245],
        owner,
    );
    if state.has_water(thing) {
        canvas.rect(
            window.0,
            window.1 + (window.3 - window.1) * 0.35,
            window.2,
            window.3,
            water_colour,
            water,
        );
    }
}

fn draw_cloth(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let state = p.scene.state;
    let OnScreen { u, v, w, h, held } = *at;
    let owner = p.owner;
    let col = p.col;
    let thing = p.thing;
    let stripe = shade(col, 0.7);
    if let Some(target) = state.covers(thing) {
        if let Some((x0, y0, x1, y1)) = covered_box(p.scene, target) {
            let (cw, ch) = (x1 - x0, y1 - y0);
            let drape = [
                (x0 - cw * 0.08, y0 - ch * 0.08),
                (x1 + cw * 0.08, y0 - ch * 0.08),
                (x1 + cw * 0.1, y0 + ch * 0.68),
                (x0 - cw * 0.1, y0 + ch * 0.68),
            ];
            outline(owner, canvas, &drape, col);
            for k in 1..4 {
                let x = x0 + cw * k as f32 / 4.0;
                canvas.line(
                    (x, y0 - ch * 0.06),
                    (x, y0 + ch * 0.66),
                    (cw * 0.03).max(1.0),
                    stripe,
                    owner,
                );
            }
        }
    } else {
        let fold = if held { w * 0.5 } else { w };
        let hh = if held { fold * 0.6 } else { h + w * 0.12 };
        outline(
            owner,
            canvas,
            &[
                (u - fold / 2.0, v - hh),
                (u + fold / 2.0, v - hh),
                (u + fold / 2.0, v),
                (u - fold / 2.0, v),
            ],
            col,
        );
        canvas.line(
            (u - fold / 2.0, v - hh * 0.5),
            (u + fold / 2.0, v - hh * 0.5),
            (hh * 0.15).max(1.0),
            stripe,
            owner,
        );
    }
}

fn draw_book(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    let owner = p.owner;
    let col = p.col;
    outline(owner, canvas, &at.front(w * 0.15), col);
    canvas.rect(u - w / 2.0, v - h, u + w / 2.0, v, [240, 236, 220], owner);
    canvas.rect(
        u - w / 2.0,
        v - h - w * 0.15,
        u - w * 0.38,
        v,
        shade(col, 0.6),
        owner,
    );
}

fn draw_remote(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    let owner = p.owner;
    let col = p.col;
    outline(owner, canvas, &at.front(w * 0.1), col);
    canvas.ellipse(u - w * 0.3, v - h, w * 0.05, w * 0.04, [220, 40, 40], owner);
    canvas.ellipse(u, v - h, w * 0.05, w * 0.04, [60, 160, 220], owner);
}

fn draw_basket(canvas: &mut Canvas, p: &Paint<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    let owner = p.owner;
    let col = p.col;
    let dark = p.dark;
    canvas.line(
        (u - w * 0.35, v - h),
        (u, v - h * 1.5),
        w * 0.05 + 1.0,
        dark,
        owner,
    );
    canvas.line(
        (u, v - h * 1.5),
        (u + w * 0.35, v - h),
        w * 0.05 + 1.0,
        dark,
        owner,
    );
    outline(
        owner,
        canvas,
        &[
            (u - w / 2.0, v - h),
            (u + w / 2.0, v - h),
            (u + w * 0.4, v),
            (u - w * 0.4, v),
        ],
        col,
    );
    for k in 1..4 {
        let y = v - h * k as f32 / 4.0;
        canvas.line(
            (u - w * 0.45, y),
            (u + w * 0.45, y),
            (h * 0.04).max(1.0),
            dark,
            owner,
        );
    }
}

/// The screen box of a covered thing, where a cloth is draped.
fn covered_box(scene: &Scene, target: ThingId) -> Option<(f32, f32, f32, f32)> {
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
