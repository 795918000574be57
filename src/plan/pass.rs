//! The passes of a frame, named by their stage and light: what timings are recorded under and
//! what reports sum by, without parsing strings back.

use serde::{Serialize, Serializer};
use std::fmt;

/// What a pass (or a CPU stage of the frame) does.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Stage {
    /// A light's casters drawn into its shadow map (one view or cube face).
    ShadowMap,
    /// The frame's depth copied into the shadow map texture.
    DepthCopy,
    /// The unlit world: depth and baked light.
    Base,
    /// The depth read back (or reduced) for the planner.
    Occlusion,
    /// A light's shadow volumes built on the CPU.
    VolumeBuild,
    /// The planner's per-frame decisions on every light's volume pieces, and the uploads.
    VolumePieces,
    /// A light's light-volume subdivision made current: its key checked, and where the light
    /// or its geometry changed, built (or read from the disk cache) and uploaded.
    Subdivision,
    /// A light's volumes counted (or the subdivision's shadowed fragments marked) into the
    /// stencil buffer.
    Stencil,
    /// The hybrid's classification: its computation mask marked into the stencil.
    Classify,
    /// A light's additive pass.
    Lit,
    /// The fill quad that darkens where the stencil is set.
    Fill,
}

impl Stage {
    /// The stage's name in reports and JSON (`lit`, `shadow_map`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Stage::ShadowMap => "shadow_map",
            Stage::DepthCopy => "depth_copy",
            Stage::Base => "base",
            Stage::Occlusion => "occlusion",
            Stage::VolumeBuild => "volume_build",
            Stage::VolumePieces => "volume_pieces",
            Stage::Subdivision => "subdivision",
            Stage::Stencil => "stencil",
            Stage::Classify => "classify",
            Stage::Lit => "lit",
            Stage::Fill => "fill",
        }
    }

    const ALL: [Stage; 11] = [
        Stage::ShadowMap,
        Stage::DepthCopy,
        Stage::Base,
        Stage::Occlusion,
        Stage::VolumeBuild,
        Stage::VolumePieces,
        Stage::Subdivision,
        Stage::Stencil,
        Stage::Classify,
        Stage::Lit,
        Stage::Fill,
    ];

    /// The stage named `name`, if any.
    pub fn from_name(name: &str) -> Option<Stage> {
        Stage::ALL.into_iter().find(|s| s.name() == name)
    }
}

/// One pass of a frame: its stage, and the light it runs for (None: a frame-wide pass).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct PassId {
    pub stage: Stage,
    pub light: Option<usize>,
}

impl PassId {
    /// A frame-wide pass.
    pub const fn frame(stage: Stage) -> PassId {
        PassId { stage, light: None }
    }

    /// A light's pass.
    pub const fn light(light: usize, stage: Stage) -> PassId {
        PassId {
            stage,
            light: Some(light),
        }
    }

    /// The name in reports: `base`, `light3.lit`; per-light passes summed over lights are
    /// reported as `lights.lit` (see [`PassId::summed_name`]).
    pub fn parse(name: &str) -> Option<PassId> {
        match name.split_once('.') {
            Some((light, stage)) => {
                let light = light.strip_prefix("light")?.parse().ok()?;
                Some(PassId::light(light, Stage::from_name(stage)?))
            }
            None => Some(PassId::frame(Stage::from_name(name)?)),
        }
    }

    /// The name under which reports sum this pass over lights: `lights.<stage>` for a light's
    /// pass, the stage's name otherwise.
    pub fn summed_name(self) -> String {
        match self.light {
            Some(_) => format!("lights.{}", self.stage.name()),
            None => self.stage.name().to_string(),
        }
    }
}

impl fmt::Display for PassId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.light {
            Some(l) => write!(f, "light{l}.{}", self.stage.name()),
            None => f.write_str(self.stage.name()),
        }
    }
}

impl Serialize for PassId {
    fn serialize<S: Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.collect_str(self)
    }
}

/// Which clock timed a pass.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Clock {
    /// GL_TIME_ELAPSED queries.
    Gpu,
    /// Wall time around glFinish, or CPU-only work.
    Cpu,
}

/// Time spent in one pass of a frame.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct PassTime {
    /// Serialized as its report name (`base`, `light0.lit`).
    #[serde(rename = "name")]
    pub pass: PassId,
    pub ms: f64,
    pub clock: Clock,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_read_back_as_the_pass_they_name() {
        for stage in Stage::ALL {
            for pass in [PassId::frame(stage), PassId::light(12, stage)] {
                assert_eq!(PassId::parse(&pass.to_string()), Some(pass));
            }
        }
        assert_eq!(PassId::light(3, Stage::Lit).to_string(), "light3.lit");
        assert_eq!(PassId::light(3, Stage::Lit).summed_name(), "lights.lit");
        assert_eq!(PassId::parse("lightx.lit"), None);
        assert_eq!(PassId::parse("light1.glow"), None);
    }
}
