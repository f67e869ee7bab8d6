//! `scene::Scene::parse` on JSON text, then `Scene::load` against a folder of tiny meshes
//! (generated meshes only up to 20,000 vertices): no panic, and every error one line naming the
//! scene file.
#![no_main]

use libfuzzer_sys::fuzz_target;
use shapeup_core::scene::SceneFormat;

fuzz_target!(|data: &[u8]| shapeup_fuzz::scene::fuzz_scene(data, SceneFormat::Json, "fuzz.json"));
