//! The sentence -> signature parser (inverse items' action text) and the signature grammar the
//! error analysis parses into components.
#![no_main]

use enact_hub::core::error_analysis::component::Component;
use enact_hub::core::scene_graph::sentence::parse_action;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(signatures) = parse_action(text) {
        for signature in &signatures {
            // What the sentence parser produces is inside the signature grammar, and a
            // component prints back as a sentence.
            let component = Component::parse(signature).unwrap_or_else(|e| {
                panic!("{text:?} gave {signature:?}, outside the grammar: {e}")
            });
            let _ = component.sentence();
        }
    }
    if let Ok(component) = Component::parse(text) {
        let _ = component.sentence();
        let _ = component.hand();
    }
});
