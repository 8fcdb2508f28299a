//! Object names as they appear in signatures and action sentences ("the top cabinet" for
//! `top_cabinet_tynnnw_1`), bit-exact with ENACT's `_format_object_name`.
//!
//! Python's `str.isdigit`, `str.isalpha` and `str.lower` are Unicode-aware; we use Rust's
//! closest equivalents (`char::is_numeric`, `char::is_alphabetic`, `to_lowercase`). They agree
//! on ASCII, which is all BEHAVIOR object names use; for exotic non-ASCII names (e.g. '½',
//! which Python does not count as a digit) results may differ.

use std::sync::LazyLock;

use rustc_hash::FxHashSet;

/// A name ENACT cannot format.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum NameError {
    /// Every underscore-separated part was dropped (e.g. `"_1"`). ENACT prints a message and
    /// calls `exit()` here, ending the whole process; we report it instead.
    #[error("object name {name:?} has no part left after formatting (ENACT exits on this)")]
    NothingLeft { name: String },
}

/// ENACT quirk: the 273 six-letter words that are kept inside a multi-part name. Any other
/// six-character part after the first is taken for a generated instance id (like `tynnnw` in
/// `top_cabinet_tynnnw_1`) and dropped, so real words such as "plates" disappear too.
pub const WHITELIST_6: [&str; 273] = [
    "cutter", "broken", "paving", "marker", "napkin", "edible", "tablet", "saddle", "flower",
    "wooden", "square", "peeler", "shovel", "nickel", "pestle", "gravel", "french", "sesame",
    "bleach", "pewter", "outlet", "fabric", "staple", "banana", "almond", "masher", "carpet",
    "fridge", "swivel", "normal", "potato", "litter", "button", "pomelo", "hanger", "trophy",
    "drying", "hamper", "radish", "grater", "pillow", "skates", "canvas", "cloche", "nutmeg",
    "indoor", "slicer", "lotion", "rolled", "starch", "chives", "tomato", "dinner", "tartar",
    "goblet", "polish", "liners", "runner", "danish", "tissue", "shaped", "tassel", "quartz",
    "muffin", "lights", "hoodie", "burlap", "wrench", "shorts", "hotdog", "lemons", "turnip",
    "cookie", "salmon", "abacus", "guitar", "paddle", "boxers", "cherry", "liquid", "helmet",
    "folder", "silver", "record", "floors", "middle", "eraser", "hinged", "carton", "wicker",
    "coffee", "smoker", "tender", "zipper", "public", "pastry", "mallet", "mussel", "flakes",
    "system", "snacks", "pebble", "cereal", "mixing", "window", "sandal", "orange", "toilet",
    "fennel", "cooker", "puzzle", "oyster", "switch", "barley", "funnel", "blower", "infant",
    "shaker", "sensor", "butter", "jigger", "ground", "mirror", "soccer", "pallet", "garage",
    "longue", "urinal", "celery", "bikini", "shears", "dental", "waffle", "handle", "noodle",
    "stairs", "easter", "socket", "boiled", "poster", "drawer", "chisel", "holder", "tackle",
    "breast", "pickle", "plugin", "jigsaw", "collar", "mortar", "pepper", "teapot", "trowel",
    "credit", "screen", "boxing", "walker", "garlic", "laptop", "server", "deicer", "omelet",
    "pruner", "makeup", "chaise", "shrimp", "tennis", "feeder", "sticky", "gloves", "yogurt",
    "pencil", "icicle", "powder", "carafe", "leaves", "jersey", "ginger", "bucket", "diaper",
    "shower", "grains", "medium", "pellet", "honing", "dahlia", "gaming", "chilli", "router",
    "icetea", "pickup", "figure", "baking", "cymbal", "violin", "frying", "bottle", "kettle",
    "spirit", "ticket", "washer", "burner", "durian", "carrot", "statue", "basket", "blouse",
    "roller", "squash", "webcam", "candle", "jacket", "ladder", "kidney", "thread", "dipper",
    "loofah", "tights", "branch", "ripsaw", "pommel", "heater", "cactus", "peanut", "canned",
    "walnut", "pillar", "cooler", "cloves", "hammer", "wreath", "hummus", "hiking", "letter",
    "teacup", "cotton", "weight", "fillet", "juicer", "cheese", "crayon", "bottom", "garden",
    "tinsel", "camera", "wading", "analog", "sponge", "wallet", "center", "locker", "copper",
    "tripod", "filter", "raisin", "rubber", "ribbon", "hockey", "beaker", "catsup", "output",
    "sodium", "turkey", "quiche", "vacuum", "saucer", "papaya", "sliced", "hammam", "grated",
    "racket", "motion", "onesie",
];

/// Parts after which a short `r<digits>` part is an agent id worth keeping ("robot r1").
const AGENT_WORDS: [&str; 3] = ["robot", "agent", "player"];

/// Python's `str.isdigit` on a whole string (false when empty).
fn all_digits(s: &str) -> bool {
    !s.is_empty() && s.chars().all(char::is_numeric)
}

/// Python's `str.isalpha` on a whole string (false when empty).
fn all_alpha(s: &str) -> bool {
    !s.is_empty() && s.chars().all(char::is_alphabetic)
}

/// ENACT's `_is_strange_string`: a six-character part that is not a whitelisted word.
pub fn is_strange_string(part: &str) -> bool {
    // A set, not a scan of 273 words: every six-letter part of every name asks.
    static WHITELIST: LazyLock<FxHashSet<&str>> =
        LazyLock::new(|| WHITELIST_6.iter().copied().collect());
    part.chars().count() == 6 && !WHITELIST.contains(part)
}

/// `_remove_trailing_numbers`: strips trailing digits; an all-digit part is returned whole.
fn strip_trailing_digits(part: &str) -> &str {
    let trimmed = part.trim_end_matches(char::is_numeric);
    if trimmed.is_empty() { part } else { trimmed }
}

/// ENACT's `_process_name_part`: what a part of a multi-part name contributes, if anything.
fn kept_part<'a>(part: &'a str, position: usize, parts: &[&str]) -> Option<&'a str> {
    if part.is_empty() || all_digits(part) {
        return None;
    }
    if position > 0
        && parts[..position].iter().any(|p| AGENT_WORDS.contains(p))
        && let Some(id) = part.strip_prefix('r')
        && part.chars().count() <= 3
        && all_digits(id)
    {
        return Some(part);
    }
    if position != 0 && is_strange_string(part) {
        return None;
    }
    let cleaned = strip_trailing_digits(part);
    if cleaned.chars().count() >= 2 && all_alpha(cleaned) {
        return Some(cleaned);
    }
    if part.chars().count() <= 3 && all_alpha(part) {
        return Some(part);
    }
    None
}

/// ENACT's `_format_object_name`: lower-cases, splits on `_`, drops numeric parts, trailing
/// digits and six-letter ids, keeps robot ids, and prefixes "the ".
pub fn format_object_name(name: &str) -> Result<String, NameError> {
    if name.is_empty() {
        return Ok("the object".to_string());
    }
    let lower = name.to_lowercase();
    let parts: Vec<&str> = lower.split('_').collect();
    if let [single] = parts.as_slice() {
        // One part: every digit is removed, unless nothing would be left.
        let cleaned: String = single.chars().filter(|c| !c.is_numeric()).collect();
        let cleaned = if cleaned.is_empty() {
            single.to_string()
        } else {
            cleaned
        };
        return Ok(format!("the {cleaned}"));
    }
    let kept: Vec<&str> = parts
        .iter()
        .enumerate()
        .filter_map(|(i, part)| kept_part(part, i, &parts))
        .collect();
    if kept.is_empty() {
        return Err(NameError::NothingLeft {
            name: name.to_string(),
        });
    }
    Ok(format!("the {}", kept.join(" ")))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn f(name: &str) -> String {
        format_object_name(name).unwrap()
    }

    #[test]
    fn whitelist_has_273_distinct_six_letter_words() {
        let set: std::collections::BTreeSet<&str> = WHITELIST_6.iter().copied().collect();
        assert_eq!(set.len(), 273);
        assert!(WHITELIST_6.iter().all(|w| w.len() == 6 && all_alpha(w)));
    }

    #[test]
    fn documented_examples() {
        assert_eq!(f("robot_r1"), "the robot r1");
        assert_eq!(f("top_cabinet_tynnnw_1"), "the top cabinet");
        assert_eq!(f("cooked__diced__cabbage"), "the cooked diced cabbage");
        assert_eq!(f("food_processor_90"), "the food processor");
        assert_eq!(f("half_apple_1"), "the half apple");
    }

    #[test]
    fn empty_and_single_part_names() {
        assert_eq!(f(""), "the object");
        assert_eq!(f("Apple12"), "the apple");
        assert_eq!(f("a1b2"), "the ab");
        assert_eq!(f("123"), "the 123");
        assert_eq!(f("dust"), "the dust");
    }

    #[test]
    fn numeric_and_empty_parts_are_dropped() {
        assert_eq!(f("plate_93"), "the plate");
        assert_eq!(f("wine__glass_21"), "the wine glass");
        assert_eq!(
            format_object_name("_12_"),
            Err(NameError::NothingLeft {
                name: "_12_".to_string()
            })
        );
    }

    #[test]
    fn robot_ids_are_kept_only_after_agent_words() {
        assert_eq!(f("agent_r12"), "the agent r12");
        assert_eq!(f("player_x_r3"), "the player x r3");
        // Not after an agent word: "r1" loses its digit, and one letter alone is not kept
        // because the part itself ("r1") is not alphabetic.
        assert_eq!(f("box_r1"), "the box");
        // Longer than three characters: not an id, and dropped for the same reason.
        assert_eq!(f("robot_r123"), "the robot");
        // Bare "r" has no digits after it.
        assert_eq!(f("robot_r"), "the robot r");
    }

    #[test]
    fn six_letter_parts() {
        assert_eq!(f("dinner_plates_1"), "the dinner");
        assert_eq!(f("bottle_of_milk_3"), "the bottle of milk");
        // The first part is never dropped for being six letters long.
        assert_eq!(f("plates_1"), "the plates");
        assert_eq!(f("bowl_abc123"), "the bowl");
        assert!(is_strange_string("tynnnw"));
        assert!(!is_strange_string("fridge"));
        assert!(!is_strange_string("apple"));
    }

    #[test]
    fn trailing_digits_and_mixed_parts() {
        assert_eq!(f("pan_processor90"), "the pan processor");
        // Digits inside a part make it non-alphabetic: dropped unless short and alphabetic.
        assert_eq!(f("pan_a1b2"), "the pan");
        assert_eq!(f("pan_x"), "the pan x");
        assert_eq!(f("pan_x-y"), "the pan");
        assert_eq!(f("Cooked__Bacon"), "the cooked bacon");
    }
}
