//! The house: its two rooms, the furniture and objects in them (names as BEHAVIOR spells them),
//! where each piece of furniture stands, and how big and what colour everything is.

/// Index of a thing in [`CATALOGUE`].
pub type ThingId = usize;

/// A room of the house; the robot's camera looks at one room during an activity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Room {
    Kitchen,
    LivingRoom,
}

/// How a thing is drawn (and, for furniture, what it can do).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Look {
    Counter,
    Cabinet,
    Stove,
    Sofa,
    CoffeeTable,
    Lamp,
    Plate,
    Bowl,
    Mug,
    Apple,
    HalfApple,
    Board,
    Knife,
    Pan,
    Bacon,
    Kettle,
    Cloth,
    Book,
    Remote,
    Basket,
    Water,
}

/// One thing of the house.
#[derive(Debug, Clone, Copy)]
pub struct Thing {
    /// The scene-graph node name.
    pub name: &'static str,
    pub category: &'static str,
    pub room: Room,
    pub look: Look,
    /// Width, height, depth in metres.
    pub size: [f32; 3],
    pub colour: [u8; 3],
    /// Furniture only: the left-bottom-front corner (x, y, z) in the room's coordinates
    /// (x to the right, y up, z away from the camera, which stands at x = 0, z = 0).
    pub at: Option<[f32; 3]>,
}

impl Thing {
    pub fn is_furniture(&self) -> bool {
        self.at.is_some()
    }
}

const fn furniture(
    name: &'static str,
    category: &'static str,
    room: Room,
    look: Look,
    at: [f32; 3],
    size: [f32; 3],
    colour: [u8; 3],
) -> Thing {
    Thing {
        name,
        category,
        room,
        look,
        size,
        colour,
        at: Some(at),
    }
}

/// How much larger than life small items are made: at real size a 9 cm apple is 16 px across
/// in a 512 px frame that shows the whole kitchen, too small to judge a change by.
const SMALL_ITEM_SCALE: f32 = 1.6;

const fn item(
    name: &'static str,
    category: &'static str,
    room: Room,
    look: Look,
    size: [f32; 3],
    colour: [u8; 3],
) -> Thing {
    let scale = if size[0] < 0.2 && size[2] < 0.2 {
        SMALL_ITEM_SCALE
    } else {
        1.0
    };
    Thing {
        name,
        category,
        room,
        look,
        size: [size[0] * scale, size[1] * scale, size[2] * scale],
        colour,
        at: None,
    }
}

use Look as L;
use Room::{Kitchen, LivingRoom};

pub const COUNTERTOP: ThingId = 0;
pub const CABINET: ThingId = 1;
pub const STOVE: ThingId = 2;
pub const PLATE: ThingId = 3;
pub const BOWL: ThingId = 4;
pub const MUG: ThingId = 5;
pub const APPLE: ThingId = 6;
pub const HALF_APPLE_0: ThingId = 7;
pub const HALF_APPLE_1: ThingId = 8;
pub const BOARD: ThingId = 9;
pub const KNIFE: ThingId = 10;
pub const PAN: ThingId = 11;
pub const BACON: ThingId = 12;
pub const KETTLE: ThingId = 13;
pub const DISHTOWEL: ThingId = 14;
pub const WATER: ThingId = 15;
pub const SOFA: ThingId = 16;
pub const COFFEE_TABLE: ThingId = 17;
pub const LAMP: ThingId = 18;
pub const BOOK: ThingId = 19;
pub const REMOTE: ThingId = 20;
pub const BASKET: ThingId = 21;
pub const BLANKET: ThingId = 22;

/// Everything in the house, in scene-graph node order (after the robot). Every category
/// occurs once except the two apple halves: ENACT drops edges between objects whose category
/// is ambiguous in view, so a world meant for QA keeps categories distinct.
pub const CATALOGUE: [Thing; 23] = [
    furniture(
        "countertop_0",
        "countertop",
        Kitchen,
        L::Counter,
        [-1.5, 0.0, 2.4],
        [2.0, 0.9, 0.6],
        [196, 170, 132],
    ),
    furniture(
        "top_cabinet_0",
        "top_cabinet",
        Kitchen,
        L::Cabinet,
        [-1.35, 1.45, 2.7],
        [0.95, 0.6, 0.3],
        [150, 98, 60],
    ),
    furniture(
        "stove_0",
        "stove",
        Kitchen,
        L::Stove,
        [0.55, 0.0, 2.4],
        [0.8, 0.9, 0.6],
        [225, 225, 228],
    ),
    item(
        "plate_0",
        "plate",
        Kitchen,
        L::Plate,
        [0.24, 0.03, 0.24],
        [246, 246, 240],
    ),
    item(
        "bowl_0",
        "bowl",
        Kitchen,
        L::Bowl,
        [0.17, 0.08, 0.17],
        [236, 226, 205],
    ),
    item(
        "mug_0",
        "mug",
        Kitchen,
        L::Mug,
        [0.09, 0.11, 0.09],
        [200, 50, 50],
    ),
    item(
        "apple_0",
        "apple",
        Kitchen,
        L::Apple,
        [0.09, 0.09, 0.09],
        [210, 30, 40],
    ),
    item(
        "half_apple_0",
        "half_apple",
        Kitchen,
        L::HalfApple,
        [0.095, 0.05, 0.095],
        [210, 30, 40],
    ),
    item(
        "half_apple_1",
        "half_apple",
        Kitchen,
        L::HalfApple,
        [0.095, 0.05, 0.095],
        [210, 30, 40],
    ),
    item(
        "chopping_board_0",
        "chopping_board",
        Kitchen,
        L::Board,
        [0.36, 0.03, 0.25],
        [160, 110, 60],
    ),
    item(
        "carving_knife_0",
        "carving_knife",
        Kitchen,
        L::Knife,
        [0.26, 0.03, 0.04],
        [170, 175, 185],
    ),
    item(
        "frying_pan_0",
        "frying_pan",
        Kitchen,
        L::Pan,
        [0.28, 0.05, 0.28],
        [45, 45, 50],
    ),
    item(
        "bacon_0",
        "bacon",
        Kitchen,
        L::Bacon,
        [0.14, 0.03, 0.06],
        [240, 140, 150],
    ),
    item(
        "kettle_0",
        "kettle",
        Kitchen,
        L::Kettle,
        [0.18, 0.22, 0.16],
        [190, 195, 205],
    ),
    item(
        "dishtowel_0",
        "dishtowel",
        Kitchen,
        L::Cloth,
        [0.3, 0.03, 0.2],
        [40, 160, 150],
    ),
    item(
        "water",
        "System",
        Kitchen,
        L::Water,
        [0.0, 0.0, 0.0],
        [60, 140, 235],
    ),
    furniture(
        "sofa_0",
        "sofa",
        LivingRoom,
        L::Sofa,
        [-1.6, 0.0, 2.7],
        [1.5, 0.85, 0.7],
        [120, 90, 160],
    ),
    furniture(
        "coffee_table_0",
        "coffee_table",
        LivingRoom,
        L::CoffeeTable,
        [-0.2, 0.0, 1.95],
        [1.1, 0.45, 0.5],
        [130, 85, 50],
    ),
    furniture(
        "floor_lamp_0",
        "floor_lamp",
        LivingRoom,
        L::Lamp,
        [1.1, 0.0, 2.8],
        [0.4, 1.65, 0.4],
        [90, 90, 95],
    ),
    item(
        "book_0",
        "book",
        LivingRoom,
        L::Book,
        [0.22, 0.05, 0.16],
        [30, 90, 60],
    ),
    item(
        "remote_control_0",
        "remote_control",
        LivingRoom,
        L::Remote,
        [0.18, 0.03, 0.06],
        [30, 30, 35],
    ),
    item(
        "basket_0",
        "basket",
        LivingRoom,
        L::Basket,
        [0.36, 0.24, 0.28],
        [205, 160, 90],
    ),
    item(
        "blanket_0",
        "blanket",
        LivingRoom,
        L::Cloth,
        [0.6, 0.06, 0.4],
        [210, 120, 60],
    ),
];

/// Things that open and close.
pub fn is_openable(thing: ThingId) -> bool {
    thing == CABINET
}

/// Things that switch on and off.
pub fn is_toggleable(thing: ThingId) -> bool {
    matches!(thing, STOVE | LAMP)
}

/// Things something can be put on, and how many sit side by side on them.
pub fn surface_slots(thing: ThingId) -> Option<usize> {
    match thing {
        COUNTERTOP => Some(7),
        STOVE => Some(2),
        SOFA => Some(4),
        COFFEE_TABLE => Some(4),
        PLATE | BOARD | PAN => Some(2),
        _ => None,
    }
}

/// Things something can be put inside (when open).
pub fn is_container(thing: ThingId) -> bool {
    thing == CABINET
}

/// Things something can be put under.
pub fn has_room_under(thing: ThingId) -> bool {
    thing == COFFEE_TABLE
}

/// Cloths, which cover things.
pub fn is_cloth(thing: ThingId) -> bool {
    matches!(thing, DISHTOWEL | BLANKET)
}

/// Things that hold water poured into them.
pub fn holds_water(thing: ThingId) -> bool {
    matches!(thing, MUG | BOWL)
}

/// Things that cook on a hot pan.
pub fn is_cookable(thing: ThingId) -> bool {
    thing == BACON
}

/// Things a knife slices, and the halves they become.
pub fn halves_of(thing: ThingId) -> Option<[ThingId; 2]> {
    (thing == APPLE).then_some([HALF_APPLE_0, HALF_APPLE_1])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_name_their_things_and_categories_are_distinct() {
        for (id, name) in [
            (COUNTERTOP, "countertop_0"),
            (CABINET, "top_cabinet_0"),
            (STOVE, "stove_0"),
            (PLATE, "plate_0"),
            (BOWL, "bowl_0"),
            (MUG, "mug_0"),
            (APPLE, "apple_0"),
            (HALF_APPLE_0, "half_apple_0"),
            (HALF_APPLE_1, "half_apple_1"),
            (BOARD, "chopping_board_0"),
            (KNIFE, "carving_knife_0"),
            (PAN, "frying_pan_0"),
            (BACON, "bacon_0"),
            (KETTLE, "kettle_0"),
            (DISHTOWEL, "dishtowel_0"),
            (WATER, "water"),
            (SOFA, "sofa_0"),
            (COFFEE_TABLE, "coffee_table_0"),
            (LAMP, "floor_lamp_0"),
            (BOOK, "book_0"),
            (REMOTE, "remote_control_0"),
            (BASKET, "basket_0"),
            (BLANKET, "blanket_0"),
        ] {
            assert_eq!(CATALOGUE[id].name, name);
        }
        let mut categories: Vec<&str> = CATALOGUE.iter().map(|t| t.category).collect();
        categories.sort_unstable();
        categories.dedup();
        assert_eq!(
            categories.len(),
            CATALOGUE.len() - 1,
            "only the halves share one"
        );
    }
}
