//! What each of the frame's passes says about itself, once, in its own
//! module: its name, the module of the paper's Table 1 it is timed under,
//! and the effect switch that turns it off (with the key a viewer binds
//! to it). Table 1, the HUD, the viewer's keys and help, and the profiler
//! iterate over [`FRAME_PASSES`].

use crate::{
    composite, edge_aa, gbuffer, lighting, march, probe, sgfit, shade, shadow, sky_behind,
};

/// The modules of the paper's Table 1, in its order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Table1Module {
    /// Rendering the field.
    NerfRendering,
    /// Tracing the incident light.
    Lighting,
    /// Fitting the SG lobes.
    SgUpdating,
    /// Rasterising and shading the object.
    Rendering,
    /// Putting the object into the field's image.
    Compositing,
    /// The shadow cast onto the field.
    Shadow,
}

impl Table1Module {
    /// Every module, in Table 1's order.
    pub const ALL: [Table1Module; 6] = [
        Table1Module::NerfRendering,
        Table1Module::Lighting,
        Table1Module::SgUpdating,
        Table1Module::Rendering,
        Table1Module::Compositing,
        Table1Module::Shadow,
    ];

    /// The module's name, as Table 1 prints it.
    pub fn name(self) -> &'static str {
        match self {
            Table1Module::NerfRendering => "NeRF rendering",
            Table1Module::Lighting => "Lighting",
            Table1Module::SgUpdating => "SG updating",
            Table1Module::Rendering => "Rendering",
            Table1Module::Compositing => "Compositing",
            Table1Module::Shadow => "Shadow",
        }
    }
}

/// An effect a frame can leave out, switched between frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Effect {
    /// The distant light L_env in the probe and the direct lobes.
    Environment,
    /// Self-shadows on the objects (eq. 9).
    SelfShadow,
    /// Shadows cast onto the field (eq. 7-8).
    CastShadow,
    /// The field hides the objects where it is in front of them (eq. 6).
    Occlusion,
    /// The objects' outlines anti-aliased (beyond the paper).
    EdgeAa,
}

impl Effect {
    /// How many effects there are.
    pub const COUNT: usize = 5;

    /// The effect's index in [`super::Effects`].
    pub fn index(self) -> usize {
        self as usize
    }
}

/// How a viewer shows and switches an effect.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EffectSwitch {
    /// The effect.
    pub effect: Effect,
    /// Its short name (HUD, help).
    pub name: &'static str,
    /// The key that switches it, as a label (`F1`).
    pub key: &'static str,
}

/// What one pass of the frame says about itself.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PassInfo {
    /// The pass's name in the frame graph, timings and traces.
    pub name: &'static str,
    /// The Table 1 module it is timed under.
    pub module: Table1Module,
    /// The effect switch that leaves it out, if any.
    pub switch: Option<EffectSwitch>,
}

/// The frame's passes, in the order a frame runs them.
pub const FRAME_PASSES: [PassInfo; 14] = [
    probe::PROBE_TRACE_INFO,
    sgfit::SG_FIT_INFO,
    lighting::DIRECT_LIGHT_INFO,
    gbuffer::OBJECT_GBUFFER_INFO,
    march::NERF_MARCH_INFO,
    shade::OBJECT_FIELD_LIGHT_INFO,
    shade::OBJECT_SHADE_INFO,
    shadow::CAST_SHADOW_INFO,
    shadow::SHADOW_UPSAMPLE_INFO,
    shadow::SHADOW_REFINE_INFO,
    composite::COMPOSITE_INFO,
    composite::COMPOSITE_REFINED_INFO,
    edge_aa::OBJECT_EDGE_AA_INFO,
    sky_behind::SKY_BEHIND_INFO,
];

/// Table 1's modules in order, each with the names of its passes.
pub fn table1() -> Vec<(&'static str, Vec<&'static str>)> {
    Table1Module::ALL
        .iter()
        .map(|&m| {
            let passes = FRAME_PASSES.iter().filter(|p| p.module == m);
            (m.name(), passes.map(|p| p.name).collect())
        })
        .collect()
}

/// Every effect switch of the frame's passes, once each, in the order of
/// [`Effect`].
pub fn effect_switches() -> Vec<EffectSwitch> {
    let mut switches: Vec<EffectSwitch> = Vec::new();
    for s in FRAME_PASSES.iter().filter_map(|p| p.switch) {
        if !switches.iter().any(|k| k.effect == s.effect) {
            switches.push(s);
        }
    }
    switches.sort_by_key(|s| s.effect.index());
    switches
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_keys_and_effects_are_declared_once() {
        let names: Vec<_> = FRAME_PASSES.iter().map(|p| p.name).collect();
        for (i, n) in names.iter().enumerate() {
            assert!(!names[i + 1..].contains(n), "pass `{n}` twice");
        }
        let switches = effect_switches();
        assert_eq!(switches.len(), Effect::COUNT, "every effect has a switch");
        for (i, s) in switches.iter().enumerate() {
            assert_eq!(s.effect.index(), i);
            for t in &switches[i + 1..] {
                assert_ne!(s.key, t.key, "{} and {} share a key", s.name, t.name);
                assert_ne!(s.name, t.name);
            }
        }
        // Two passes that share an effect declare the same switch.
        for p in FRAME_PASSES.iter().filter_map(|p| p.switch) {
            assert_eq!(Some(&p), switches.iter().find(|s| s.effect == p.effect));
        }
    }

    #[test]
    fn table1_groups_every_pass_once_in_order() {
        let t = table1();
        assert_eq!(t.len(), 6);
        assert_eq!(
            t[0],
            (
                "NeRF rendering",
                vec![march::NERF_MARCH, sky_behind::SKY_BEHIND]
            )
        );
        assert_eq!(
            t[5],
            (
                "Shadow",
                vec![
                    shadow::CAST_SHADOW,
                    shadow::SHADOW_UPSAMPLE,
                    shadow::SHADOW_REFINE
                ]
            )
        );
        let count: usize = t.iter().map(|(_, p)| p.len()).sum();
        assert_eq!(count, FRAME_PASSES.len());
    }
}
