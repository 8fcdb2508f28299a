//! The drawings: the robot's arms, boxes, and one painter per look in the catalogue (fixed
//! furniture drawn at its place in the room, movable things at their anchor on screen).

use crate::world::render::CameraRig;
use crate::world::render::layout::{Anchor, Camera, OnScreen, Scene, covered_box, project_rect};
use crate::world::render::primitives::{Canvas, ROBOT_OWNER, owner_of, shade};
use crate::world::state::{Hand, WorldState};
use crate::world::things::{self, CATALOGUE, Look, Thing, ThingId};

/// The robot's two arms reaching from the bottom corners to its grippers.
pub(super) fn draw_arms(canvas: &mut Canvas, camera: &Camera, rig: &CameraRig) {
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

/// Paints one thing where its anchor puts it.
pub(super) fn draw_thing(canvas: &mut Canvas, scene: &Scene, thing: ThingId, anchor: Anchor) {
    let spec = &CATALOGUE[thing];
    let mut p = Painter {
        canvas,
        scene,
        camera: &scene.camera,
        state: scene.state,
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
            Look::Counter => draw_counter(&mut p, at),
            Look::Cabinet => draw_cabinet(&mut p, at, anchor),
            Look::Stove => draw_stove(&mut p, at),
            Look::Sofa => draw_sofa(&mut p, at),
            Look::CoffeeTable => draw_coffee_table(&mut p, at),
            Look::Lamp => draw_lamp(&mut p, at),
            _ => p.solid_box(at, spec.size, spec.colour),
        }
        return;
    }
    let Some((u, v, mut s)) = scene.camera.project(anchor.at) else {
        return;
    };
    let [w0, h0, _] = spec.size;
    if anchor.held {
        // Carried things are drawn at a legible size rather than their true one up close.
        s = s.min(p.canvas.size as f32 * 0.3 / w0.max(0.05));
    }
    let at = OnScreen {
        u,
        v,
        w: w0 * s,
        h: h0 * s,
        held: anchor.held,
    };
    match spec.look {
        Look::Plate => draw_plate(&mut p, &at),
        Look::Bowl => draw_bowl(&mut p, &at),
        Look::Mug => draw_mug(&mut p, &at),
        Look::Apple => draw_apple(&mut p, &at),
        Look::HalfApple => draw_half_apple(&mut p, &at),
        Look::Board => draw_board(&mut p, &at),
        Look::Knife => draw_knife(&mut p, &at),
        Look::Pan => draw_pan(&mut p, &at),
        Look::Bacon => draw_bacon(&mut p, &at),
        Look::Kettle => draw_kettle(&mut p, &at),
        Look::Cloth => draw_cloth(&mut p, &at),
        Look::Book => draw_book(&mut p, &at),
        Look::Remote => draw_remote(&mut p, &at),
        Look::Basket => draw_basket(&mut p, &at),
        _ => {}
    }
}

/// One thing being painted: the canvas, the scene, the thing and its catalogue entry, and its
/// colours. What it paints is marked with the thing's owner id; water it holds, with water's.
struct Painter<'a> {
    canvas: &'a mut Canvas,
    scene: &'a Scene<'a>,
    camera: &'a Camera,
    state: &'a WorldState,
    thing: ThingId,
    spec: &'static Thing,
    owner: u16,
    col: [u8; 3],
    dark: [u8; 3],
    water: u16,
    water_colour: [u8; 3],
}

impl Painter<'_> {
    fn polygon(&mut self, pts: &[(f32, f32)], colour: [u8; 3]) {
        self.canvas.polygon(pts, colour, self.owner);
    }

    fn rect(&mut self, x0: f32, y0: f32, x1: f32, y1: f32, colour: [u8; 3]) {
        self.canvas.rect(x0, y0, x1, y1, colour, self.owner);
    }

    fn ellipse(&mut self, cx: f32, cy: f32, rx: f32, ry: f32, colour: [u8; 3]) {
        self.canvas.ellipse(cx, cy, rx, ry, colour, self.owner);
    }

    fn lower_half_ellipse(&mut self, cx: f32, cy: f32, rx: f32, ry: f32, colour: [u8; 3]) {
        self.canvas
            .lower_half_ellipse(cx, cy, rx, ry, colour, self.owner);
    }

    fn line(&mut self, a: (f32, f32), b: (f32, f32), width: f32, colour: [u8; 3]) {
        self.canvas.line(a, b, width, colour, self.owner);
    }

    fn outline(&mut self, pts: &[(f32, f32)], fill: [u8; 3]) {
        self.canvas.outline(pts, fill, self.owner);
    }

    fn solid_box(&mut self, at: [f32; 3], size: [f32; 3], colour: [u8; 3]) {
        draw_box(self.canvas, self.camera, at, size, colour, self.owner);
    }
}

fn draw_counter(p: &mut Painter<'_>, at: [f32; 3]) {
    let [w, _, _] = p.spec.size;
    p.solid_box(at, p.spec.size, p.col);
    for i in 0..4 {
        let x = at[0] + w * (i as f32 + 0.5) / 4.0;
        if let Some((u0, v0, u1, v1)) =
            project_rect(p.camera, x - 0.2, at[1] + 0.1, x + 0.2, at[1] + 0.75, at[2])
        {
            p.rect(u0, v0, u1, v1, shade(p.col, 0.92));
            p.rect(u0, v0 + (v1 - v0) * 0.1, u1, v0 + (v1 - v0) * 0.14, p.dark);
        }
    }
}

fn draw_cabinet(p: &mut Painter<'_>, at: [f32; 3], anchor: Anchor) {
    let [w, h, _] = p.spec.size;
    if anchor.key > at[2] {
        // The body first; the contents and then the door are painted later.
        p.solid_box(at, p.spec.size, p.col);
        if let Some((u0, v0, u1, v1)) = project_rect(
            p.camera,
            at[0] + 0.03,
            at[1] + 0.03,
            at[0] + w - 0.03,
            at[1] + h - 0.03,
            at[2],
        ) {
            p.rect(u0, v0, u1, v1, [60, 42, 30]);
            let mid = (v0 + v1) / 2.0;
            p.rect(u0, mid - 2.0, u1, mid + 2.0, shade(p.col, 0.8));
        }
    } else if p.state.is_open(p.thing) {
        // Swung 100 degrees about the left hinge, towards the camera.
        let (dx, dz) = (w * -0.1736, -w * 0.9848);
        let pts: Vec<(f32, f32)> = [
            [at[0], at[1], at[2]],
            [at[0] + dx, at[1], at[2] + dz],
            [at[0] + dx, at[1] + h, at[2] + dz],
            [at[0], at[1] + h, at[2]],
        ]
        .iter()
        .filter_map(|corner| p.camera.project(*corner).map(|(u, v, _)| (u, v)))
        .collect();
        if pts.len() == 4 {
            p.polygon(&pts, shade(p.col, 0.85));
        }
    } else if let Some((u0, v0, u1, v1)) =
        project_rect(p.camera, at[0], at[1], at[0] + w, at[1] + h, at[2])
    {
        p.rect(u0, v0, u1, v1, p.col);
        p.rect(u0 + 3.0, v0 + 3.0, u1 - 3.0, v1 - 3.0, shade(p.col, 1.1));
        let knob = (u1 - (u1 - u0) * 0.1, (v0 + v1) / 2.0);
        p.ellipse(knob.0, knob.1, 4.0, 4.0, [230, 200, 120]);
    }
}

fn draw_stove(p: &mut Painter<'_>, at: [f32; 3]) {
    let [w, h, d] = p.spec.size;
    p.solid_box(at, p.spec.size, p.col);
    let on = p.state.is_on(p.thing);
    for bx in [0.25f32, 0.75] {
        if let Some((u, v, s)) = p
            .camera
            .project([at[0] + w * bx, at[1] + h, at[2] + d * 0.5])
        {
            let hot = on;
            p.ellipse(u, v, 0.14 * s, 0.05 * s, [30, 30, 30]);
            if hot {
                p.ellipse(u, v, 0.12 * s, 0.04 * s, [255, 70, 20]);
                p.ellipse(u, v, 0.06 * s, 0.02 * s, [255, 200, 60]);
            } else {
                p.ellipse(u, v, 0.09 * s, 0.03 * s, [70, 70, 72]);
            }
        }
    }
    if let Some((u0, v0, u1, v1)) = project_rect(
        p.camera,
        at[0] + 0.08,
        at[1] + 0.1,
        at[0] + w - 0.08,
        at[1] + 0.6,
        at[2],
    ) {
        // A switched-on stove shows it across its whole front: the oven window glows.
        let window = if on { [255, 130, 40] } else { [40, 40, 46] };
        p.rect(u0, v0, u1, v1, window);
    }
    for k in 0..3 {
        if let Some((u, v, s)) =
            p.camera
                .project([at[0] + w * (0.25 + 0.25 * k as f32), at[1] + 0.78, at[2]])
        {
            let knob = if on && k == 0 {
                [255, 90, 30]
            } else {
                [60, 60, 60]
            };
            p.ellipse(u, v, 0.035 * s, 0.035 * s, knob);
        }
    }
}

fn draw_sofa(p: &mut Painter<'_>, at: [f32; 3]) {
    let [w, h, d] = p.spec.size;
    p.solid_box(
        [at[0], at[1] + 0.45, at[2] + d - 0.2],
        [w, h - 0.45, 0.2],
        shade(p.col, 0.9),
    );
    p.solid_box(at, [w, 0.45, d], p.col);
    p.solid_box(
        [at[0] - 0.12, at[1], at[2]],
        [0.12, 0.62, d],
        shade(p.col, 0.8),
    );
    p.solid_box(
        [at[0] + w, at[1], at[2]],
        [0.12, 0.62, d],
        shade(p.col, 0.8),
    );
}

fn draw_coffee_table(p: &mut Painter<'_>, at: [f32; 3]) {
    let [w, h, d] = p.spec.size;
    for (lx, lz) in [
        (0.05, 0.05),
        (w - 0.1, 0.05),
        (0.05, d - 0.1),
        (w - 0.1, d - 0.1),
    ] {
        p.solid_box(
            [at[0] + lx, 0.0, at[2] + lz],
            [0.05, h - 0.05, 0.05],
            p.dark,
        );
    }
    p.solid_box([at[0], h - 0.06, at[2]], [w, 0.06, d], p.col);
}

fn draw_lamp(p: &mut Painter<'_>, at: [f32; 3]) {
    let [w, h, d] = p.spec.size;
    let cx = at[0] + w / 2.0;
    let cz = at[2] + d / 2.0;
    let on = p.state.is_on(p.thing);
    if on && let Some((u, v, s)) = p.camera.project([cx, h - 0.12, cz]) {
        p.ellipse(u, v, 0.55 * s, 0.5 * s, [250, 240, 170]);
        p.ellipse(u, v, 0.38 * s, 0.34 * s, [255, 248, 200]);
    }
    if let Some((u, v, s)) = p.camera.project([cx, 0.0, cz]) {
        p.ellipse(u, v, 0.16 * s, 0.05 * s, p.dark);
    }
    if let (Some(a), Some(b)) = (
        p.camera.project([cx, 0.0, cz]),
        p.camera.project([cx, h - 0.25, cz]),
    ) {
        p.line((a.0, a.1), (b.0, b.1), 0.035 * a.2, p.dark);
    }
    if let (Some((u0, v0, s)), Some((_, v1, _))) = (
        p.camera.project([cx, h - 0.3, cz]),
        p.camera.project([cx, h, cz]),
    ) {
        let shade_colour = if on { [255, 226, 90] } else { [236, 228, 206] };
        p.polygon(
            &[
                (u0 - 0.2 * s, v0),
                (u0 + 0.2 * s, v0),
                (u0 + 0.12 * s, v1),
                (u0 - 0.12 * s, v1),
            ],
            shade_colour,
        );
    }
}

fn draw_plate(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    p.ellipse(
        u,
        v - h / 2.0,
        w / 2.0 + 1.5,
        (w * 0.16).max(h) + 1.5,
        [120, 120, 120],
    );
    p.ellipse(u, v - h / 2.0, w / 2.0, (w * 0.16).max(h), p.col);
    p.ellipse(
        u,
        v - h / 2.0,
        w * 0.32,
        (w * 0.1).max(h * 0.6),
        [232, 232, 226],
    );
}

fn draw_bowl(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    p.lower_half_ellipse(u, v - h, w / 2.0 + 1.5, h + 1.5, shade(p.col, 0.5));
    p.lower_half_ellipse(u, v - h, w / 2.0, h, p.col);
    p.ellipse(u, v - h, w / 2.0, w * 0.14, shade(p.col, 1.3));
    if p.state.has_water(p.thing) {
        // Filled: water splashes up over the rim, then fills the bowl to the brim.
        for k in 0..6 {
            let k = k as f32;
            p.canvas.ellipse(
                u + (k - 2.5) * w * 0.17,
                v - h - w * (0.25 + 0.12 * (2.5 - (k - 2.5).abs())),
                w * 0.12,
                w * 0.12,
                p.water_colour,
                p.water,
            );
        }
        p.canvas
            .ellipse(u, v - h, w * 0.6, w * 0.2, [200, 228, 250], p.water);
        p.canvas
            .ellipse(u, v - h, w * 0.48, w * 0.13, p.water_colour, p.water);
        p.canvas.lower_half_ellipse(
            u,
            v - h,
            w * 0.44,
            h * 0.8,
            shade(p.water_colour, 0.85),
            p.water,
        );
        p.canvas.ellipse(
            u - w * 0.15,
            v - h,
            w * 0.12,
            w * 0.04,
            [235, 245, 255],
            p.water,
        );
    } else {
        p.ellipse(u, v - h, w * 0.42, w * 0.1, shade(p.col, 0.7));
    }
}

fn draw_mug(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    p.ellipse(
        u + w * 0.55,
        v - h * 0.5,
        w * 0.28,
        h * 0.28,
        shade(p.col, 0.6),
    );
    p.outline(&at.front(0.0), p.col);
    let full = p.state.has_water(p.thing);
    let rim = if full {
        (p.water_colour, p.water)
    } else {
        ([80, 20, 20], p.owner)
    };
    p.canvas.ellipse(u, v - h, w / 2.0, w * 0.16, rim.0, rim.1);
    if full {
        // Steam over a filled mug: tea is visible at thumbnail size.
        for k in 0..5 {
            let k = k as f32;
            p.canvas.ellipse(
                u + (k % 2.0 - 0.5) * w * 0.5,
                v - h - w * (0.45 + 0.5 * k),
                w * 0.6,
                w * 0.36,
                [245, 245, 250],
                p.water,
            );
        }
    }
}

fn draw_apple(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, .. } = *at;
    p.ellipse(u, v - w / 2.0, w / 2.0 + 1.5, w / 2.0 + 1.5, [110, 10, 20]);
    p.ellipse(u, v - w / 2.0, w / 2.0, w / 2.0, p.col);
    p.line(
        (u, v - w),
        (u + w * 0.1, v - w * 1.25),
        w * 0.08,
        [90, 60, 30],
    );
    p.ellipse(
        u + w * 0.22,
        v - w * 1.12,
        w * 0.16,
        w * 0.08,
        [60, 160, 60],
    );
}

fn draw_half_apple(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    // Juice on the surface under a freshly cut half.
    p.ellipse(u, v, w * 0.95, w * 0.3, [240, 170, 170]);
    p.lower_half_ellipse(u, v - h, w / 2.0 + 1.5, h + 1.5, [110, 10, 20]);
    p.lower_half_ellipse(u, v - h, w / 2.0, h, p.col);
    // The cut face, turned to the camera: pale flesh and the core.
    p.ellipse(u, v - h, w / 2.0, w * 0.34, [250, 240, 200]);
    p.ellipse(u, v - h, w * 0.1, w * 0.07, [120, 80, 40]);
}

fn draw_board(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    let top = w * 0.18;
    p.outline(&at.front(top), p.col);
    p.rect(u - w / 2.0, v - h, u + w / 2.0, v, shade(p.col, 0.8));
}

fn draw_knife(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    let blade = [
        (u - w / 2.0, v - h),
        (u + w * 0.1, v - h * 1.6),
        (u + w * 0.1, v),
        (u - w / 2.0, v),
    ];
    p.outline(&blade, p.col);
    p.rect(u + w * 0.1, v - h * 1.2, u + w / 2.0, v, [40, 30, 25]);
}

fn draw_pan(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    p.line(
        (u + w * 0.4, v - h),
        (u + w * 0.95, v - h * 1.4),
        h * 0.5 + 2.0,
        [30, 30, 30],
    );
    p.ellipse(u, v - h / 2.0, w / 2.0 + 1.5, w * 0.17 + 1.5, [20, 20, 20]);
    p.ellipse(u, v - h / 2.0, w / 2.0, w * 0.17, p.col);
    p.ellipse(u, v - h / 2.0, w * 0.4, w * 0.12, shade(p.col, 1.4));
}

fn draw_bacon(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    let c = if p.state.is_cooked(p.thing) {
        [150, 75, 35]
    } else {
        p.col
    };
    let fat = if p.state.is_cooked(p.thing) {
        [200, 150, 90]
    } else {
        [252, 225, 220]
    };
    if p.state.is_cooked(p.thing) {
        // Cooked bacon has curled and rendered its fat: a crisp dark halo around the strips
        // makes the change read at thumbnail size.
        p.ellipse(u, v - h * 1.6, w * 0.72, h * 3.2 + w * 0.12, [95, 50, 20]);
        p.ellipse(u, v - h * 1.6, w * 0.62, h * 2.6 + w * 0.08, [185, 120, 55]);
    }
    for k in 0..2 {
        let y = v - h * (1.0 + k as f32 * 1.3);
        p.outline(
            &[
                (u - w / 2.0, y - h),
                (u + w / 2.0, y - h * 1.3),
                (u + w / 2.0, y),
                (u - w / 2.0, y + h * 0.3),
            ],
            c,
        );
        p.line(
            (u - w / 2.0, y - h * 0.4),
            (u + w / 2.0, y - h * 0.7),
            (h * 0.25).max(1.0),
            fat,
        );
    }
}

fn draw_kettle(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    p.polygon(
        &[
            (u + w * 0.35, v - h * 0.5),
            (u + w * 0.75, v - h * 0.95),
            (u + w * 0.75, v - h * 0.85),
            (u + w * 0.35, v - h * 0.3),
        ],
        shade(p.col, 0.7),
    );
    p.outline(
        &[
            (u - w / 2.0, v),
            (u + w / 2.0, v),
            (u + w * 0.38, v - h * 0.85),
            (u - w * 0.38, v - h * 0.85),
        ],
        p.col,
    );
    p.line(
        (u - w * 0.3, v - h * 0.85),
        (u, v - h * 1.1),
        h * 0.07 + 1.0,
        [40, 40, 40],
    );
    p.line(
        (u, v - h * 1.1),
        (u + w * 0.3, v - h * 0.85),
        h * 0.07 + 1.0,
        [40, 40, 40],
    );
    let window = (u - w * 0.2, v - h * 0.7, u + w * 0.1, v - h * 0.1);
    p.rect(window.0, window.1, window.2, window.3, [230, 240, 245]);
    if p.state.has_water(p.thing) {
        p.canvas.rect(
            window.0,
            window.1 + (window.3 - window.1) * 0.35,
            window.2,
            window.3,
            p.water_colour,
            p.water,
        );
    }
}

fn draw_cloth(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, held } = *at;
    let stripe = shade(p.col, 0.7);
    if let Some(target) = p.state.covers(p.thing) {
        if let Some((x0, y0, x1, y1)) = covered_box(p.scene, target) {
            let (cw, ch) = (x1 - x0, y1 - y0);
            let drape = [
                (x0 - cw * 0.08, y0 - ch * 0.08),
                (x1 + cw * 0.08, y0 - ch * 0.08),
                (x1 + cw * 0.1, y0 + ch * 0.68),
                (x0 - cw * 0.1, y0 + ch * 0.68),
            ];
            p.outline(&drape, p.col);
            for k in 1..4 {
                let x = x0 + cw * k as f32 / 4.0;
                p.line(
                    (x, y0 - ch * 0.06),
                    (x, y0 + ch * 0.66),
                    (cw * 0.03).max(1.0),
                    stripe,
                );
            }
        }
    } else {
        let fold = if held { w * 0.5 } else { w };
        let hh = if held { fold * 0.6 } else { h + w * 0.12 };
        p.outline(
            &[
                (u - fold / 2.0, v - hh),
                (u + fold / 2.0, v - hh),
                (u + fold / 2.0, v),
                (u - fold / 2.0, v),
            ],
            p.col,
        );
        p.line(
            (u - fold / 2.0, v - hh * 0.5),
            (u + fold / 2.0, v - hh * 0.5),
            (hh * 0.15).max(1.0),
            stripe,
        );
    }
}

fn draw_book(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    p.outline(&at.front(w * 0.15), p.col);
    p.rect(u - w / 2.0, v - h, u + w / 2.0, v, [240, 236, 220]);
    p.rect(
        u - w / 2.0,
        v - h - w * 0.15,
        u - w * 0.38,
        v,
        shade(p.col, 0.6),
    );
}

fn draw_remote(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    p.outline(&at.front(w * 0.1), p.col);
    p.ellipse(u - w * 0.3, v - h, w * 0.05, w * 0.04, [220, 40, 40]);
    p.ellipse(u, v - h, w * 0.05, w * 0.04, [60, 160, 220]);
}

fn draw_basket(p: &mut Painter<'_>, at: &OnScreen) {
    let OnScreen { u, v, w, h, .. } = *at;
    p.line(
        (u - w * 0.35, v - h),
        (u, v - h * 1.5),
        w * 0.05 + 1.0,
        p.dark,
    );
    p.line(
        (u, v - h * 1.5),
        (u + w * 0.35, v - h),
        w * 0.05 + 1.0,
        p.dark,
    );
    p.outline(
        &[
            (u - w / 2.0, v - h),
            (u + w / 2.0, v - h),
            (u + w * 0.4, v),
            (u - w * 0.4, v),
        ],
        p.col,
    );
    for k in 1..4 {
        let y = v - h * k as f32 / 4.0;
        p.line(
            (u - w * 0.45, y),
            (u + w * 0.45, y),
            (h * 0.04).max(1.0),
            p.dark,
        );
    }
}
