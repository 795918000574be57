//! The legacy OpenGL entry points the fixed-function pipeline calls, which glow does not have:
//! loaded by name from a compatibility-profile context (`gl.pipeline = fixed_function`).
//!
//! Each is the GL 1.x call the paper names: glAlphaFunc (alpha test), glTexGen (eye-linear
//! texture coordinates), glClipPlane, glTexEnv (ARB_multitexture combiners), glLight /
//! glMaterial (per-vertex lighting), the matrix stack, client vertex arrays and glRect. The
//! enums below are those of GL 1.x / ARB_shadow / ARB_texture_env_combine that glow omits.

use std::ffi::{CStr, c_void};

type Enum = u32;
type AlphaFunc = unsafe extern "system" fn(Enum, f32);
type TexGeni = unsafe extern "system" fn(Enum, Enum, i32);
type TexGenfv = unsafe extern "system" fn(Enum, Enum, *const f32);
type ClipPlane = unsafe extern "system" fn(Enum, *const f64);
type TexEnvi = unsafe extern "system" fn(Enum, Enum, i32);
type TexEnvfv = unsafe extern "system" fn(Enum, Enum, *const f32);
type MatrixMode = unsafe extern "system" fn(Enum);
type LoadMatrixf = unsafe extern "system" fn(*const f32);
type Lightfv = unsafe extern "system" fn(Enum, Enum, *const f32);
type Lightf = unsafe extern "system" fn(Enum, Enum, f32);
type LightModelfv = unsafe extern "system" fn(Enum, *const f32);
type LightModeli = unsafe extern "system" fn(Enum, i32);
type Materialfv = unsafe extern "system" fn(Enum, Enum, *const f32);
type Color4f = unsafe extern "system" fn(f32, f32, f32, f32);
type Pointer = unsafe extern "system" fn(i32, Enum, i32, *const c_void);
type ColorPointer = Pointer;
type NormalPointer = unsafe extern "system" fn(Enum, i32, *const c_void);
type ClientState = unsafe extern "system" fn(Enum);
type Rectf = unsafe extern "system" fn(f32, f32, f32, f32);

pub const ALPHA_TEST: Enum = 0x0BC0;
pub const TEXTURE_GEN_S: Enum = 0x0C60;
pub const TEXTURE_GEN_T: Enum = 0x0C61;
pub const TEXTURE_GEN_R: Enum = 0x0C62;
pub const TEXTURE_GEN_Q: Enum = 0x0C63;
pub const S: Enum = 0x2000;
pub const T: Enum = 0x2001;
pub const R: Enum = 0x2002;
pub const Q: Enum = 0x2003;
pub const TEXTURE_GEN_MODE: Enum = 0x2500;
pub const EYE_LINEAR: Enum = 0x2400;
pub const EYE_PLANE: Enum = 0x2502;
pub const CLIP_PLANE0: Enum = 0x3000;
/// ARB_depth_texture: how a compare result is returned (ALPHA, INTENSITY or LUMINANCE).
pub const DEPTH_TEXTURE_MODE: Enum = 0x884B;
pub const ALPHA: Enum = 0x1906;
pub const INTENSITY: Enum = 0x8049;
pub const TEXTURE_ENV: Enum = 0x2300;
pub const TEXTURE_ENV_MODE: Enum = 0x2200;
pub const MODULATE: Enum = 0x2100;
pub const REPLACE: Enum = 0x1E01;
pub const COMBINE: Enum = 0x8570;
pub const COMBINE_RGB: Enum = 0x8571;
pub const COMBINE_ALPHA: Enum = 0x8572;
pub const RGB_SCALE: Enum = 0x8573;
pub const SOURCE0_RGB: Enum = 0x8580;
pub const SOURCE1_RGB: Enum = 0x8581;
pub const SOURCE0_ALPHA: Enum = 0x8588;
pub const SOURCE1_ALPHA: Enum = 0x8589;
pub const OPERAND0_RGB: Enum = 0x8590;
pub const OPERAND1_RGB: Enum = 0x8591;
pub const OPERAND0_ALPHA: Enum = 0x8598;
pub const OPERAND1_ALPHA: Enum = 0x8599;
pub const PRIMARY_COLOR: Enum = 0x8577;
pub const PREVIOUS: Enum = 0x8578;
pub const TEXTURE: Enum = 0x1702;
pub const SRC_COLOR: Enum = 0x0300;
pub const SRC_ALPHA: Enum = 0x0302;
pub const MODELVIEW: Enum = 0x1700;
pub const PROJECTION: Enum = 0x1701;
pub const LIGHTING: Enum = 0x0B50;
pub const LIGHT0: Enum = 0x4000;
pub const AMBIENT: Enum = 0x1200;
pub const DIFFUSE: Enum = 0x1201;
pub const SPECULAR: Enum = 0x1202;
pub const POSITION: Enum = 0x1203;
pub const SPOT_DIRECTION: Enum = 0x1204;
pub const SPOT_EXPONENT: Enum = 0x1205;
pub const SPOT_CUTOFF: Enum = 0x1206;
pub const CONSTANT_ATTENUATION: Enum = 0x1207;
pub const LINEAR_ATTENUATION: Enum = 0x1208;
pub const QUADRATIC_ATTENUATION: Enum = 0x1209;
pub const LIGHT_MODEL_AMBIENT: Enum = 0x0B53;
pub const LIGHT_MODEL_TWO_SIDE: Enum = 0x0B52;
pub const FRONT_AND_BACK: Enum = 0x0408;
pub const NORMALIZE: Enum = 0x0BA1;
pub const VERTEX_ARRAY: Enum = 0x8074;
pub const NORMAL_ARRAY: Enum = 0x8075;
pub const COLOR_ARRAY: Enum = 0x8076;
pub const TEXTURE_COORD_ARRAY: Enum = 0x8078;

/// The loaded entry points; every pointer was non-null when loaded.
pub struct Legacy {
    pub alpha_func: AlphaFunc,
    pub tex_gen_i: TexGeni,
    pub tex_gen_fv: TexGenfv,
    pub clip_plane: ClipPlane,
    pub tex_env_i: TexEnvi,
    pub tex_env_fv: TexEnvfv,
    pub matrix_mode: MatrixMode,
    pub load_matrix_f: LoadMatrixf,
    pub light_fv: Lightfv,
    pub light_f: Lightf,
    pub light_model_fv: LightModelfv,
    pub light_model_i: LightModeli,
    pub material_fv: Materialfv,
    pub color_4f: Color4f,
    pub vertex_pointer: Pointer,
    pub normal_pointer: NormalPointer,
    pub color_pointer: ColorPointer,
    pub tex_coord_pointer: Pointer,
    pub enable_client_state: ClientState,
    pub disable_client_state: ClientState,
    pub client_active_texture: ClientState,
    pub rect_f: Rectf,
}

/// Loads one entry point as `F`, or names it when the context lacks it.
///
/// SAFETY (caller): `F` must be the function pointer type of the GL command `name`.
unsafe fn entry<F: Copy>(
    load: &mut impl FnMut(&CStr) -> *const c_void,
    name: &CStr,
    missing: &mut Vec<String>,
) -> Option<F> {
    let p = load(name);
    if p.is_null() {
        missing.push(name.to_string_lossy().into_owned());
        return None;
    }
    debug_assert_eq!(
        std::mem::size_of::<F>(),
        std::mem::size_of::<*const c_void>()
    );
    // SAFETY: a non-null address of the command whose type the caller names.
    Some(unsafe { std::mem::transmute_copy::<*const c_void, F>(&p) })
}

impl Legacy {
    /// Loads every entry point through `load` (the context's GetProcAddress); the error names
    /// those it lacks. The context must be current and a compatibility profile: a core
    /// context may still hand out addresses whose calls raise INVALID_OPERATION, which
    /// [`Legacy::check`] catches.
    pub fn load(mut load: impl FnMut(&CStr) -> *const c_void) -> Result<Legacy, String> {
        let mut missing = Vec::new();
        let l = &mut load;
        let m = &mut missing;
        // SAFETY: each type alias is the signature of the command loaded into it.
        let legacy = unsafe {
            (|| {
                Some(Legacy {
                    alpha_func: entry(l, c"glAlphaFunc", m)?,
                    tex_gen_i: entry(l, c"glTexGeni", m)?,
                    tex_gen_fv: entry(l, c"glTexGenfv", m)?,
                    clip_plane: entry(l, c"glClipPlane", m)?,
                    tex_env_i: entry(l, c"glTexEnvi", m)?,
                    tex_env_fv: entry(l, c"glTexEnvfv", m)?,
                    matrix_mode: entry(l, c"glMatrixMode", m)?,
                    load_matrix_f: entry(l, c"glLoadMatrixf", m)?,
                    light_fv: entry(l, c"glLightfv", m)?,
                    light_f: entry(l, c"glLightf", m)?,
                    light_model_fv: entry(l, c"glLightModelfv", m)?,
                    light_model_i: entry(l, c"glLightModeli", m)?,
                    material_fv: entry(l, c"glMaterialfv", m)?,
                    color_4f: entry(l, c"glColor4f", m)?,
                    vertex_pointer: entry(l, c"glVertexPointer", m)?,
                    normal_pointer: entry(l, c"glNormalPointer", m)?,
                    color_pointer: entry(l, c"glColorPointer", m)?,
                    tex_coord_pointer: entry(l, c"glTexCoordPointer", m)?,
                    enable_client_state: entry(l, c"glEnableClientState", m)?,
                    disable_client_state: entry(l, c"glDisableClientState", m)?,
                    client_active_texture: entry(l, c"glClientActiveTexture", m)?,
                    rect_f: entry(l, c"glRectf", m)?,
                })
            })()
        };
        legacy.ok_or_else(|| format!("the context lacks {}", missing.join(", ")))
    }

    /// Sets the alpha function, toggles GL_ALPHA_TEST and reads the error flag: a core-profile
    /// context answers INVALID_OPERATION or INVALID_ENUM, a compatibility profile nothing.
    pub fn check(&self, gl: &glow::Context) -> Result<(), String> {
        use glow::HasContext;
        const ALPHA_TEST: u32 = 0x0BC0;
        // SAFETY: the context is current; the alpha function and test are left at GL's
        // defaults.
        let error = unsafe {
            while gl.get_error() != glow::NO_ERROR {}
            (self.alpha_func)(glow::GREATER, 0.5);
            gl.enable(ALPHA_TEST);
            gl.disable(ALPHA_TEST);
            let error = gl.get_error();
            (self.alpha_func)(glow::ALWAYS, 0.0);
            while gl.get_error() != glow::NO_ERROR {}
            error
        };
        if error == glow::NO_ERROR {
            Ok(())
        } else {
            Err(format!(
                "glAlphaFunc / GL_ALPHA_TEST raised GL error 0x{error:x}: the context is not a \
                 compatibility profile"
            ))
        }
    }

    /// Loads `m` into the matrix stack `mode` (column-major, as glam stores it).
    ///
    /// # Safety
    /// The compatibility context these were loaded from must be current.
    pub unsafe fn load_matrix(&self, mode: Enum, m: &glam::Mat4) {
        // SAFETY: the caller's context is current; the array holds 16 floats.
        unsafe {
            (self.matrix_mode)(mode);
            (self.load_matrix_f)(m.to_cols_array().as_ptr());
        }
    }

    /// Sets a texture environment parameter of the active texture unit.
    ///
    /// # Safety
    /// The compatibility context these were loaded from must be current.
    pub unsafe fn env(&self, name: Enum, value: Enum) {
        // SAFETY: see the function's contract.
        unsafe { (self.tex_env_i)(TEXTURE_ENV, name, value as i32) }
    }
}
