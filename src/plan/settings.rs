//! What the GL passes read of the options, resolved for one frame: the GL layer draws what the
//! plan and these settings say and reads no `Options` itself (the choices that need a feature
//! the GL lacks, and those `plan.profile` turns off, are already taken when they are made).

use crate::options::{
    HybridOptions, LightingOptions, Options, Pipeline, ShadowMapOptions, ShadowVolumeOptions,
};

/// The option groups a frame's passes draw with.
#[derive(Debug, Clone, PartialEq)]
pub struct PassSettings {
    /// How maps are drawn, compared, filtered and offset.
    pub shadow_map: ShadowMapOptions,
    /// How volumes are extruded and counted.
    pub shadow_volume: ShadowVolumeOptions,
    /// Light intensity, attenuation and light-once marking.
    pub lighting: LightingOptions,
    /// The hybrid's computation mask and search radius.
    pub hybrid: HybridOptions,
    /// Quake 3's r_overBrightBits: the unlit pass multiplies lightmaps by 2^bits.
    pub overbright_bits: u32,
    /// The legacy fixed-function pipeline draws the frame (`gl.pipeline = fixed_function`).
    pub fixed_function: bool,
}

/// glPolygonOffset (factor, units) of the light with `order` among the shadowed lights, or None
/// when the offset is off: the paper's growth makes each subsequent light's offset larger.
pub fn map_offset(o: &ShadowMapOptions, order: usize) -> Option<(f32, f32)> {
    o.offset.then(|| {
        let k = 1.0 + o.offset_growth * order as f32;
        (o.offset_factor * k, o.offset_units * k)
    })
}

impl PassSettings {
    pub fn of(options: &Options) -> PassSettings {
        PassSettings {
            shadow_map: options.shadow_map.clone(),
            shadow_volume: options.shadow_volume.clone(),
            lighting: options.lighting.clone(),
            hybrid: options.hybrid.clone(),
            overbright_bits: options.q3.overbright_bits,
            fixed_function: options.gl.pipeline == Pipeline::FixedFunction,
        }
    }
}
