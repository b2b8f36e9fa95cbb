//! What a host hands the embedded shadow pass each frame: its G-buffer textures and the light.

use glam::{Mat4, Vec3};

use crate::scene::view::QuadLight;
use crate::{Error, Result};

/// Where the surface seen by each pixel is, in one of two forms.
#[derive(Clone, Copy, Debug)]
pub enum SurfaceInput<'a> {
    /// The host's depth buffer and the camera that rendered it. Each pixel's world
    /// position is its centre `(x + ½, y + ½)` at the stored depth, unprojected with
    /// `(projection × view)⁻¹`; texels equal to `background_depth` see no geometry.
    ///
    /// `texture`: any depth format (`Depth32Float`, `Depth24Plus`, `Depth16Unorm`,
    /// the depth aspect of a depth-stencil format), single-sampled, 2-D, with
    /// [`wgpu::TextureUsages::TEXTURE_BINDING`]. Depth-buffer rounding moves the
    /// reconstructed point along the view ray: measured up to 1.1 mm at 11 m with
    /// `Depth32Float` and the near plane at 3.5 cm (the default scene's ray offset is
    /// 1.7 mm), against 0.02 mm from a position texture; a farther near plane or reversed
    /// Z shrinks it. Prefer [`SurfaceInput::Position`] where that matters.
    Depth {
        /// The depth texture.
        texture: &'a wgpu::Texture,
        /// World-to-view matrix (its inverse gives the eye).
        view: Mat4,
        /// View-to-clip matrix in wgpu's conventions (depth 0..1, y up in NDC), e.g.
        /// `glam::camera::rh::proj::directx::perspective` (wgpu has DirectX's conventions).
        projection: Mat4,
        /// The value the depth buffer was cleared to: 1 for a standard projection,
        /// 0 for reversed Z.
        background_depth: f32,
    },
    /// A world-position texture: xyz the surface point, w = 0 where the pixel sees no
    /// geometry (anything else: a hit). Any float format that can be read unfiltered
    /// (`Rgba32Float` recommended, so positions keep full precision), single-sampled,
    /// 2-D, with [`wgpu::TextureUsages::TEXTURE_BINDING`].
    Position {
        /// The position texture.
        texture: &'a wgpu::Texture,
        /// The camera position, world space (normals are flipped towards it and the
        /// filter compares eye distances).
        eye: Vec3,
    },
}

/// How the host's normal textures store a normal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum NormalEncoding {
    /// The texels are the normal's components (a float or snorm format).
    #[default]
    Signed,
    /// The texels are `n · ½ + ½`: signed components kept in a unorm format, as Bevy's
    /// normal prepass writes them (`Rgb10a2Unorm`).
    Biased,
}

/// The host's per-frame inputs to [`super::ShadowPass::record`]. All textures are the
/// size of the [`super::ShadowTargets`] they are recorded with; row 0 is the top row.
#[derive(Clone, Copy, Debug)]
pub struct ShadowInputs<'a> {
    /// Where each pixel's surface is.
    pub surface: SurfaceInput<'a>,
    /// World-space shading normals in xyz (any length, either side: they are normalized
    /// and turned towards the camera). Any float or normalized format read unfiltered,
    /// e.g. `Rgba16Float` or `Rgba8Snorm`; a unorm format (`Rgba8Unorm`, `Rgb10a2Unorm`)
    /// only with [`NormalEncoding::Biased`], since normals are signed.
    /// The filter compares them between neighbours.
    pub normal: &'a wgpu::Texture,
    /// World-space geometric (face) normals, same formats as `normal`, or `None` to use
    /// the shading normals. They set the tangent plane below which rays count as blocked
    /// and the direction the shadow-ray origin leaves the surface; with smooth shading
    /// normals instead, pixels near a curved object's terminator differ slightly from
    /// penumbra's own renderer (which uses face normals).
    pub geometric_normal: Option<&'a wgpu::Texture>,
    /// How `normal` and `geometric_normal` store normals.
    pub normal_encoding: NormalEncoding,
    /// The quad light whose soft shadows are traced (16 rays per pixel towards the
    /// pixel's set of light samples, [`crate::sampling::light_points`]).
    pub light: &'a QuadLight,
}

impl ShadowInputs<'_> {
    /// The eye position and the clip-to-eye matrix ([`SurfaceParams::clip_to_eye`](crate::contract::layout::SurfaceParams::clip_to_eye); identity for [`SurfaceInput::Position`]).
    pub(super) fn camera(&self) -> Result<(Vec3, Mat4)> {
        match self.surface {
            SurfaceInput::Position { eye, .. } => Ok((eye, Mat4::IDENTITY)),
            SurfaceInput::Depth { view, projection, .. } => {
                // In f64, rounded once: the w row of (P·V)⁻¹ nearly cancels against depths
                // close to 1, so the matrix should add no rounding of its own.
                let view_inverse = view.inverse();
                let eye = view_inverse.w_axis.truncate();
                // Relative to the eye, so that no large translation is rounded into it.
                let clip_to_eye = (glam::DMat4::from_translation(-eye.as_dvec3())
                    * (projection.as_dmat4() * view.as_dmat4()).inverse())
                .as_mat4();
                if !view_inverse.is_finite() || !clip_to_eye.is_finite() {
                    return Err(Error::invalid(
                        "ShadowInputs::surface",
                        "the view or projection matrix is not invertible",
                    ));
                }
                Ok((eye, clip_to_eye))
            }
        }
    }

    /// Checks every texture against what the kernels bind, for a `width`×`height` frame.
    pub(super) fn check(&self, width: u32, height: u32) -> Result<()> {
        match self.surface {
            SurfaceInput::Depth { texture, .. } => {
                check_texture("ShadowInputs::surface (depth)", texture, width, height)?;
                if !texture.format().has_depth_aspect() {
                    return Err(Error::invalid(
                        "ShadowInputs::surface (depth)",
                        format!("format {:?} has no depth aspect", texture.format()),
                    ));
                }
            }
            SurfaceInput::Position { texture, .. } => {
                check_float_texture("ShadowInputs::surface (position)", texture, width, height)?;
            }
        }
        check_float_texture("ShadowInputs::normal", self.normal, width, height)?;
        if let Some(geo) = self.geometric_normal {
            check_float_texture("ShadowInputs::geometric_normal", geo, width, height)?;
        }
        Ok(())
    }
}

fn check_texture(what: &str, texture: &wgpu::Texture, width: u32, height: u32) -> Result<()> {
    let size = texture.size();
    let problem = if (size.width, size.height) != (width, height) {
        format!(
            "is {}x{}, the targets are {width}x{height}",
            size.width, size.height
        )
    } else if texture.dimension() != wgpu::TextureDimension::D2 || size.depth_or_array_layers != 1 {
        "must be a 2-D texture with one layer".to_owned()
    } else if texture.sample_count() != 1 {
        format!(
            "has {} samples per pixel; resolve it to a single-sampled texture first",
            texture.sample_count()
        )
    } else if !texture.usage().contains(wgpu::TextureUsages::TEXTURE_BINDING) {
        "needs TextureUsages::TEXTURE_BINDING".to_owned()
    } else {
        return Ok(());
    };
    Err(Error::invalid(what, format!("the texture {problem}")))
}

fn check_float_texture(what: &str, texture: &wgpu::Texture, width: u32, height: u32) -> Result<()> {
    check_texture(what, texture, width, height)?;
    match texture.format().sample_type(None, None) {
        Some(wgpu::TextureSampleType::Float { .. }) => Ok(()),
        _ => Err(Error::invalid(
            what,
            format!(
                "format {:?} cannot be read as floats (use a float or normalized colour format)",
                texture.format()
            ),
        )),
    }
}
