//! Pictures of the demo kitchen: one 512×512 frame drawn from a [`WorldState`], seen from the
//! robot's head camera with its two arms reaching in from the bottom.
//!
//! Every predicate of the state has a visible mark (door open, burner glowing, cooked colour,
//! where each object is, what each gripper holds), so different states give different frames.

use image::RgbImage;

use crate::demo::label::LabelFont;
use crate::demo::paint::{Canvas, Colour};
use crate::demo::world::{Gripper, Placement, Thing, WorldState};

/// Side of a frame in pixels (ENACT's camera resolution).
pub(crate) const FRAME_SIZE: u32 = 512;

const WALL: Colour = [236, 226, 206];
const COUNTER_BACK_Y: f32 = 292.0;
const COUNTER_FRONT_Y: f32 = 362.0;
const COUNTER_LEFT_X: f32 = 142.0;
/// Baseline of objects standing at the back of the counter.
const COUNTER_ROW_Y: f32 = 308.0;
const FRIDGE: (f32, f32, f32, f32) = (30.0, 92.0, 142.0, 500.0);
const BURNER: (f32, f32) = (453.0, 326.0);
const BOARD: (f32, f32, f32, f32) = (160.0, 330.0, 262.0, 350.0);
const PLATE: (f32, f32) = (328.0, 348.0);
const SHELF_Y: f32 = 166.0;

fn gripper_centre(gripper: Gripper) -> (f32, f32) {
    match gripper {
        Gripper::Left => (196.0, 436.0),
        Gripper::Right => (372.0, 436.0),
    }
}

/// Where the arm enters the picture.
fn shoulder(gripper: Gripper) -> (f32, f32) {
    match gripper {
        Gripper::Left => (104.0, 540.0),
        Gripper::Right => (464.0, 540.0),
    }
}

/// Half the height of an object as drawn (its centre sits this far above its support).
fn half_height(thing: Thing) -> f32 {
    match thing {
        Thing::Apple => 15.0,
        Thing::HalfApple1 | Thing::HalfApple2 => 8.0,
        Thing::Bread => 13.0,
        Thing::Mug => 16.0,
        Thing::Bacon => 6.0,
        Thing::Knife => 5.0,
        Thing::Pan => 6.0,
        _ => 0.0,
    }
}

/// Where a gripper closes on the object, relative to the object's centre, and how far apart
/// its fingers are then.
fn grip(thing: Thing) -> ((f32, f32), f32) {
    match thing {
        Thing::Knife => ((18.0, 0.0), 6.5),
        Thing::Pan => ((43.0, -6.0), 5.0),
        Thing::Bread => ((0.0, 0.0), 26.0),
        Thing::Bacon => ((0.0, 0.0), 24.0),
        Thing::Mug => ((0.0, 0.0), 14.0),
        _ => ((0.0, 0.0), 16.0),
    }
}

/// Horizontal slot of an object on a wide support, so objects never overlap.
fn slot_x(support: Thing, thing: Thing) -> f32 {
    let half_offset = match thing {
        Thing::HalfApple1 => -19.0,
        Thing::HalfApple2 => 19.0,
        _ => 0.0,
    };
    match support {
        Thing::Counter => match thing {
            Thing::Pan => 196.0,
            Thing::Bread => 282.0,
            Thing::Knife => 340.0,
            Thing::Mug => 380.0,
            _ => 384.0 + half_offset,
        },
        Thing::Shelf => match thing {
            Thing::Mug => 214.0,
            Thing::Bread => 270.0,
            _ => 312.0 + half_offset,
        },
        Thing::Fridge => match thing {
            Thing::Apple => 70.0,
            _ => 86.0 + half_offset,
        },
        Thing::CuttingBoard => (BOARD.0 + BOARD.2) / 2.0 + half_offset,
        Thing::Plate => PLATE.0 + half_offset,
        _ => half_offset,
    }
}

/// Centre of an object in the frame, following stacks down to fixed furniture or a gripper.
fn centre(state: &WorldState, thing: Thing) -> (f32, f32) {
    let below = |support: Thing, baseline: f32| (slot_x(support, thing), baseline);
    let (x, baseline) = match state.placements.get(&thing) {
        Some(Placement::HeldBy(gripper)) => {
            let (gx, gy) = gripper_centre(*gripper);
            let ((ox, oy), _) = grip(thing);
            return (gx - ox, gy - oy);
        }
        Some(Placement::Inside(_)) => {
            let shelf_y = match thing {
                Thing::Bread | Thing::Mug => 400.0,
                _ => 290.0,
            };
            below(Thing::Fridge, shelf_y)
        }
        Some(Placement::OnTop(Thing::Pan)) => {
            let (px, py) = centre(state, Thing::Pan);
            (px + slot_x(Thing::Pan, thing), py + 3.0)
        }
        Some(Placement::OnTop(Thing::Stove)) => (BURNER.0, BURNER.1 + 2.0),
        Some(Placement::OnTop(Thing::Counter)) => below(Thing::Counter, COUNTER_ROW_Y),
        Some(Placement::OnTop(Thing::Shelf)) => below(Thing::Shelf, SHELF_Y),
        Some(Placement::OnTop(Thing::CuttingBoard)) => below(Thing::CuttingBoard, 343.0),
        Some(Placement::OnTop(Thing::Plate)) => below(Thing::Plate, PLATE.1 + 1.0),
        Some(Placement::OnTop(other)) => below(*other, COUNTER_ROW_Y),
        None => (0.0, 0.0),
    };
    (x, baseline - half_height(thing))
}

/// The support an object's stack finally rests in: a gripper, the fridge, or furniture.
fn root(state: &WorldState, thing: Thing) -> Placement {
    let mut current = thing;
    for _ in 0..=state.placements.len() {
        match state.placements.get(&current) {
            Some(Placement::OnTop(support)) if state.placements.contains_key(support) => {
                current = *support;
            }
            Some(placement) => return *placement,
            None => break,
        }
    }
    Placement::OnTop(Thing::Counter)
}

/// How many movable objects are under this one (0 for an object on furniture).
fn stack_level(state: &WorldState, thing: Thing) -> usize {
    match state.placements.get(&thing) {
        Some(Placement::OnTop(support)) if state.placements.contains_key(support) => {
            1 + stack_level(state, *support)
        }
        _ => 0,
    }
}

/// Draws frames of the demo kitchen. The furniture that never changes is painted once and
/// copied into every frame.
#[derive(Clone)]
pub(crate) struct Kitchen {
    backdrop: Canvas,
}

impl Kitchen {
    pub(crate) fn new() -> Kitchen {
        let mut backdrop = Canvas::new(FRAME_SIZE, WALL);
        draw_room(&mut backdrop);
        draw_board_and_plate(&mut backdrop);
        Kitchen { backdrop }
    }

    /// The frame for a state (without any ENACT label).
    pub(crate) fn render(&self, state: &WorldState, font: &LabelFont) -> RgbImage {
        render_over(self.backdrop.clone(), state, font)
    }
}

fn render_over(mut canvas: Canvas, state: &WorldState, font: &LabelFont) -> RgbImage {
    draw_stove(&mut canvas, state.stove_on);
    draw_fridge(&mut canvas, state);

    let mut resting: Vec<Thing> = state
        .placements
        .keys()
        .copied()
        .filter(|t| matches!(root(state, *t), Placement::OnTop(_)))
        .collect();
    resting.sort_by(|a, b| {
        let key = |t: Thing| (stack_level(state, t), centre(state, t).1 as i32);
        key(*a).cmp(&key(*b))
    });
    for thing in &resting {
        let (x, y) = centre(state, *thing);
        draw_thing(&mut canvas, state, *thing, x, y);
    }
    draw_steam(&mut canvas, state);

    for gripper in [Gripper::Left, Gripper::Right] {
        draw_arm(&mut canvas, gripper);
        let mut carried: Vec<Thing> = state
            .placements
            .keys()
            .copied()
            .filter(|t| root(state, *t) == Placement::HeldBy(gripper))
            .collect();
        carried.sort_by_key(|t| stack_level(state, *t));
        for thing in &carried {
            let (x, y) = centre(state, *thing);
            draw_thing(&mut canvas, state, *thing, x, y);
        }
        let finger_gap = state.held_by(gripper).map(|t| grip(t).1);
        draw_fingers(&mut canvas, gripper, finger_gap);
    }

    let mut image = canvas.into_image();
    // Mark each wrist so left and right can be told apart at a glance.
    for (gripper, letter) in [(Gripper::Left, "L"), (Gripper::Right, "R")] {
        let (gx, gy) = gripper_centre(gripper);
        font.text(letter, gx - 6.0, gy + 25.0, 18.0, [250, 250, 250])
            .apply(&mut image);
    }
    image
}

fn draw_room(c: &mut Canvas) {
    // Range hood above the stove.
    c.polygon(
        &[(414.0, 92.0), (496.0, 92.0), (512.0, 150.0), (398.0, 150.0)],
        [178, 181, 188],
    );
    c.rect(398.0, 150.0, 512.0, 157.0, [140, 143, 150]);
    // Tiled backsplash.
    c.rect(
        COUNTER_LEFT_X,
        176.0,
        512.0,
        COUNTER_BACK_Y,
        [229, 236, 240],
    );
    let mut x = COUNTER_LEFT_X + 22.0;
    while x < 512.0 {
        c.rect(x, 176.0, x + 1.5, COUNTER_BACK_Y, [204, 212, 219]);
        x += 24.0;
    }
    let mut y = 176.0 + 24.0;
    while y < COUNTER_BACK_Y {
        c.rect(COUNTER_LEFT_X, y, 512.0, y + 1.5, [204, 212, 219]);
        y += 24.0;
    }
    // Wall shelf with brackets.
    c.rect(176.0, SHELF_Y, 344.0, SHELF_Y + 8.0, [156, 106, 66]);
    c.rect(176.0, SHELF_Y + 8.0, 344.0, SHELF_Y + 10.0, [120, 80, 48]);
    for bx in [196.0, 324.0] {
        c.polygon(
            &[
                (bx - 3.0, SHELF_Y + 10.0),
                (bx + 3.0, SHELF_Y + 10.0),
                (bx + 3.0, SHELF_Y + 26.0),
            ],
            [110, 110, 116],
        );
    }
    // Counter top, its front edge and the cabinets under it.
    c.polygon(
        &[
            (COUNTER_LEFT_X, COUNTER_BACK_Y),
            (512.0, COUNTER_BACK_Y),
            (512.0, COUNTER_FRONT_Y),
            (COUNTER_LEFT_X - 6.0, COUNTER_FRONT_Y),
        ],
        [214, 182, 135],
    );
    c.rect(
        COUNTER_LEFT_X,
        COUNTER_BACK_Y,
        512.0,
        COUNTER_BACK_Y + 2.0,
        [186, 152, 108],
    );
    c.rect(
        COUNTER_LEFT_X - 6.0,
        COUNTER_FRONT_Y,
        512.0,
        372.0,
        [174, 138, 94],
    );
    c.rect(COUNTER_LEFT_X - 6.0, 372.0, 512.0, 512.0, [126, 138, 160]);
    for door_x in [236.0, 330.0, 424.0] {
        c.rect(door_x - 1.5, 372.0, door_x + 1.5, 512.0, [98, 108, 128]);
    }
    for handle_x in [189.0, 283.0, 377.0] {
        c.round_rect(
            handle_x - 14.0,
            384.0,
            handle_x + 14.0,
            390.0,
            3.0,
            [206, 210, 216],
        );
    }
    // Floor under the fridge.
    c.rect(0.0, FRIDGE.3, COUNTER_LEFT_X, 512.0, [150, 128, 106]);
}

fn draw_stove(c: &mut Canvas, on: bool) {
    c.polygon(
        &[
            (400.0, 296.0),
            (506.0, 296.0),
            (510.0, 357.0),
            (396.0, 357.0),
        ],
        [52, 52, 58],
    );
    let (bx, by) = BURNER;
    if on {
        c.ellipse_alpha(bx, by, 54.0, 22.0, [255, 120, 30], 0.35);
        c.ellipse(bx, by, 40.0, 15.0, [255, 72, 20]);
        c.ellipse(bx, by, 29.0, 10.5, [200, 40, 10]);
        c.ellipse(bx, by, 22.0, 7.5, [255, 150, 40]);
        c.ellipse(bx, by, 10.0, 3.5, [255, 220, 120]);
    } else {
        c.ellipse(bx, by, 40.0, 15.0, [96, 96, 102]);
        c.ellipse(bx, by, 29.0, 10.5, [64, 64, 70]);
        c.ellipse(bx, by, 22.0, 7.5, [96, 96, 102]);
        c.ellipse(bx, by, 10.0, 3.5, [64, 64, 70]);
    }
    // Control knob on the cabinet front and a power light next to it.
    let (kx, ky) = (452.0, 396.0);
    c.circle(kx, ky, 11.0, [40, 40, 46]);
    c.circle(kx, ky, 8.0, [86, 86, 94]);
    let tip = if on { (kx + 9.0, ky) } else { (kx, ky - 9.0) };
    c.line((kx, ky), tip, 3.0, [235, 235, 240]);
    let light = if on { [255, 40, 30] } else { [70, 40, 40] };
    c.circle(kx + 24.0, ky, 5.0, light);
}

fn draw_board_and_plate(c: &mut Canvas) {
    let (x0, y0, x1, y1) = BOARD;
    c.round_rect(x0, y1 - 4.0, x1, y1 + 6.0, 4.0, [150, 104, 62]);
    c.round_rect(x0, y0, x1, y1, 5.0, [198, 150, 98]);
    c.rect(x0 + 8.0, y0 + 6.0, x1 - 8.0, y0 + 7.0, [180, 132, 84]);
    c.rect(x0 + 14.0, y0 + 13.0, x1 - 20.0, y0 + 14.0, [180, 132, 84]);
    let (px, py) = PLATE;
    c.ellipse(px, py + 2.0, 33.0, 11.0, [176, 176, 184]);
    c.ellipse(px, py, 33.0, 10.5, [248, 248, 250]);
    c.ellipse(px, py, 24.0, 7.0, [232, 232, 238]);
}

fn draw_fridge(c: &mut Canvas, state: &WorldState) {
    let (x0, y0, x1, y1) = FRIDGE;
    c.rect(x0, y0, x1, y1, [150, 156, 164]);
    if !state.fridge_open {
        c.rect(x0 + 3.0, y0 + 3.0, x1 - 3.0, y1 - 3.0, [228, 232, 237]);
        c.rect(x0 + 3.0, 195.0, x1 - 3.0, 198.0, [150, 156, 164]);
        c.round_rect(x1 - 18.0, 130.0, x1 - 11.0, 182.0, 3.0, [118, 124, 132]);
        c.round_rect(x1 - 18.0, 214.0, x1 - 11.0, 300.0, 3.0, [118, 124, 132]);
        return;
    }
    c.rect(x0 + 6.0, y0 + 6.0, x1 - 6.0, y1 - 6.0, [198, 218, 232]);
    c.rect(x0 + 6.0, y0 + 6.0, x1 - 6.0, y0 + 30.0, [220, 234, 242]);
    c.round_rect(72.0, y0 + 9.0, 100.0, y0 + 16.0, 3.0, [255, 246, 196]);
    c.rect(x0 + 6.0, 190.0, x1 - 6.0, 198.0, [228, 232, 237]);
    for shelf_y in [290.0, 400.0] {
        c.rect(x0 + 6.0, shelf_y, x1 - 6.0, shelf_y + 4.0, [150, 186, 208]);
    }
    c.round_rect(x0 + 10.0, 440.0, x1 - 10.0, 490.0, 4.0, [214, 228, 238]);
    c.rect(x0 + 10.0, 452.0, x1 - 10.0, 454.0, [180, 198, 212]);
    // Contents first, so the open door (hinged on the left) stays in front of nothing.
    let mut inside: Vec<Thing> = state
        .placements
        .iter()
        .filter(|(_, p)| **p == Placement::Inside(Thing::Fridge))
        .map(|(t, _)| *t)
        .collect();
    inside.sort();
    for thing in inside {
        let (x, y) = centre(state, thing);
        draw_thing(c, state, thing, x, y);
    }
    // The open door seen edge-on, swung towards the camera.
    c.polygon(
        &[(x0, y0), (2.0, 64.0), (2.0, 532.0), (x0, y1)],
        [150, 156, 164],
    );
    c.polygon(
        &[
            (x0 - 2.0, y0 + 4.0),
            (5.0, 70.0),
            (5.0, 524.0),
            (x0 - 2.0, y1 - 4.0),
        ],
        [214, 220, 228],
    );
    for bin_y in [170.0, 300.0, 420.0] {
        c.polygon(
            &[
                (x0 - 3.0, bin_y),
                (6.0, bin_y - 8.0),
                (6.0, bin_y + 14.0),
                (x0 - 3.0, bin_y + 14.0),
            ],
            [176, 196, 212],
        );
    }
}

fn draw_thing(c: &mut Canvas, state: &WorldState, thing: Thing, x: f32, y: f32) {
    match thing {
        Thing::Apple => {
            c.circle(x, y, 15.0, [196, 28, 34]);
            c.circle(x - 5.0, y - 5.0, 4.0, [236, 110, 110]);
            c.line((x, y - 12.0), (x + 2.0, y - 21.0), 3.0, [104, 66, 30]);
            c.ellipse(x + 7.0, y - 19.0, 6.0, 3.0, [70, 150, 50]);
        }
        Thing::HalfApple1 | Thing::HalfApple2 => {
            c.lower_half_ellipse(x, y - 2.0, 17.0, 11.0, [196, 28, 34]);
            c.ellipse(x, y - 2.0, 17.0, 6.5, [250, 236, 186]);
            c.ellipse(x - 3.5, y - 2.0, 2.0, 3.2, [90, 50, 20]);
            c.ellipse(x + 3.5, y - 2.0, 2.0, 3.2, [90, 50, 20]);
        }
        Thing::Bread => {
            c.round_rect(x - 25.0, y - 13.0, x + 25.0, y + 13.0, 10.0, [182, 116, 52]);
            c.ellipse(x, y - 5.0, 21.0, 6.0, [218, 162, 92]);
            for dx in [-12.0, 0.0, 12.0] {
                c.line(
                    (x + dx - 4.0, y - 1.0),
                    (x + dx + 4.0, y - 9.0),
                    2.0,
                    [146, 90, 38],
                );
            }
        }
        Thing::Mug => {
            c.line((x + 10.0, y - 9.0), (x + 20.0, y - 6.0), 4.5, [40, 86, 170]);
            c.line((x + 20.0, y - 6.0), (x + 20.0, y + 5.0), 4.5, [40, 86, 170]);
            c.line((x + 20.0, y + 5.0), (x + 10.0, y + 8.0), 4.5, [40, 86, 170]);
            c.rect(x - 12.0, y - 15.0, x + 12.0, y + 15.0, [50, 102, 192]);
            c.lower_half_ellipse(x, y + 15.0, 12.0, 3.0, [50, 102, 192]);
            c.rect(x - 12.0, y - 2.0, x + 12.0, y + 3.0, [236, 240, 248]);
            c.ellipse(x, y - 15.0, 12.0, 3.5, [36, 76, 160]);
            c.ellipse(x, y - 15.0, 9.5, 2.4, [24, 44, 92]);
        }
        Thing::Bacon => {
            let cooked = state.cooked.contains(&Thing::Bacon);
            let (body, stripe) = if cooked {
                ([146, 64, 30], [96, 38, 18])
            } else {
                ([238, 142, 142], [252, 222, 212])
            };
            let wave = |t: f32| 2.2 * (t * 0.9).sin();
            let steps = 12;
            let mut outline = Vec::with_capacity(2 * steps + 2);
            for i in 0..=steps {
                let t = i as f32;
                outline.push((x - 23.0 + t * 46.0 / steps as f32, y - 5.0 + wave(t)));
            }
            for i in (0..=steps).rev() {
                let t = i as f32;
                outline.push((x - 23.0 + t * 46.0 / steps as f32, y + 5.0 + wave(t)));
            }
            c.polygon(&outline, body);
            for offset in [-1.5, 2.0] {
                for i in 0..steps {
                    let (t0, t1) = (i as f32, i as f32 + 1.0);
                    let xa = x - 21.0 + t0 * 42.0 / steps as f32;
                    let xb = x - 21.0 + t1 * 42.0 / steps as f32;
                    c.line(
                        (xa, y + offset + wave(t0)),
                        (xb, y + offset + wave(t1)),
                        1.6,
                        stripe,
                    );
                }
            }
        }
        Thing::Knife => {
            c.polygon(
                &[
                    (x - 33.0, y + 1.0),
                    (x - 26.0, y - 5.0),
                    (x + 4.0, y - 5.0),
                    (x + 4.0, y + 5.0),
                    (x - 23.0, y + 5.0),
                ],
                [206, 212, 220],
            );
            c.line(
                (x - 26.0, y + 4.4),
                (x + 4.0, y + 4.4),
                1.2,
                [140, 146, 156],
            );
            c.rect(x + 4.0, y - 6.0, x + 8.0, y + 6.0, [120, 120, 128]);
            c.round_rect(x + 8.0, y - 4.5, x + 29.0, y + 4.5, 3.0, [44, 34, 30]);
            for rx in [13.0, 23.0] {
                c.circle(x + rx, y, 1.3, [210, 210, 214]);
            }
        }
        Thing::Pan => {
            c.line((x + 28.0, y - 2.0), (x + 55.0, y - 10.0), 6.0, [30, 30, 34]);
            c.lower_half_ellipse(x, y + 2.0, 34.0, 11.0, [26, 26, 30]);
            c.ellipse(x, y, 34.0, 11.0, [42, 42, 48]);
            c.ellipse(x, y - 1.0, 30.0, 8.5, [78, 78, 86]);
        }
        _ => {}
    }
}

/// Wisps above food in a pan on a lit stove.
fn draw_steam(c: &mut Canvas, state: &WorldState) {
    let pan_on_lit_stove = state.stove_on
        && state.placements.get(&Thing::Pan) == Some(&Placement::OnTop(Thing::Stove));
    let food_in_pan = state
        .placements
        .values()
        .any(|p| *p == Placement::OnTop(Thing::Pan));
    if !(pan_on_lit_stove && food_in_pan) {
        return;
    }
    let (px, py) = centre(state, Thing::Pan);
    for dx in [-14.0f32, 0.0, 14.0] {
        let mut previous = (px + dx, py - 12.0);
        for i in 1..=6 {
            let t = i as f32;
            let next = (px + dx + 4.0 * (t * 1.2).sin(), py - 12.0 - t * 6.0);
            c.line(previous, next, 2.5, [250, 250, 250]);
            previous = next;
        }
    }
}

fn draw_arm(c: &mut Canvas, gripper: Gripper) {
    let (gx, gy) = gripper_centre(gripper);
    let wrist = (gx, gy + 44.0);
    let start = shoulder(gripper);
    c.line(start, wrist, 44.0, [92, 98, 110]);
    c.line(start, wrist, 38.0, [238, 239, 243]);
    c.round_rect(
        gx - 20.0,
        gy + 22.0,
        gx + 20.0,
        gy + 46.0,
        6.0,
        [70, 72, 82],
    );
    c.rect(gx - 30.0, gy + 14.0, gx + 30.0, gy + 26.0, [52, 54, 62]);
}

/// The two fingers, wide open when empty or closed on a held object.
fn draw_fingers(c: &mut Canvas, gripper: Gripper, holding: Option<f32>) {
    let (gx, gy) = gripper_centre(gripper);
    let pad = match gripper {
        Gripper::Left => [240, 140, 40],
        Gripper::Right => [40, 168, 170],
    };
    let spread = holding.map_or(30.0, |gap| gap + 4.0);
    for side in [-1.0f32, 1.0] {
        let fx = gx + side * spread;
        c.round_rect(fx - 4.5, gy - 20.0, fx + 4.5, gy + 18.0, 3.0, [60, 62, 72]);
        let inner = fx - side * 3.0;
        c.round_rect(inner - 2.0, gy - 16.0, inner + 2.0, gy + 6.0, 1.5, pad);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::world::{Step, activities};

    fn differing_pixels(a: &RgbImage, b: &RgbImage) -> usize {
        a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count()
    }

    #[test]
    fn frames_are_512_square_and_every_step_changes_many_pixels() {
        let font = LabelFont::load().unwrap();
        for activity in activities() {
            let states = activity.states().unwrap();
            let kitchen = Kitchen::new();
            let frames: Vec<RgbImage> = states.iter().map(|s| kitchen.render(s, &font)).collect();
            for (i, pair) in frames.windows(2).enumerate() {
                assert_eq!(pair[0].dimensions(), (FRAME_SIZE, FRAME_SIZE));
                let changed = differing_pixels(&pair[0], &pair[1]);
                assert!(
                    changed > 150,
                    "{} step {i} ({:?}) changes only {changed} pixels",
                    activity.name,
                    activity.steps[i]
                );
            }
        }
    }

    #[test]
    fn a_lit_burner_is_orange_and_an_unlit_one_grey() {
        let font = LabelFont::load().unwrap();
        let off = activities()[0].start.clone();
        let on = off.apply(Step::TurnOnStove).unwrap();
        let (bx, by) = (BURNER.0 as u32, BURNER.1 as u32);
        let kitchen = Kitchen::new();
        let lit = kitchen.render(&on, &font).get_pixel(bx - 35, by).0;
        let dark = kitchen.render(&off, &font).get_pixel(bx - 35, by).0;
        assert!(lit[0] > 200 && lit[2] < 80, "{lit:?}");
        assert!(dark[0] < 120, "{dark:?}");
    }
}
