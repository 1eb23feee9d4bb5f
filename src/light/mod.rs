//! Light sources. A closed set of `Copy` variants; each can be sampled from a shading point.

use crate::math::{Color, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    /// Isotropic point light; `intensity` is colour x intensity in W/sr, falling off as 1/d^2.
    Point { position: Vec3, intensity: Color },
    /// Light from infinitely far away; `direction` is the unit direction the light travels,
    /// `irradiance` what a surface facing it receives.
    Directional { direction: Vec3, irradiance: Color },
}

/// Light arriving at a point from one light sample.
#[derive(Clone, Copy, Debug)]
pub struct LightSample {
    /// Unit direction from the shading point towards the light.
    pub wi: Vec3,
    /// Distance to the light along `wi` (infinite for directional lights).
    pub dist: f32,
    /// Irradiance at normal incidence carried by this sample (multiply by cos theta).
    pub irradiance: Color,
}

impl Light {
    /// The light as seen from `p`; `None` when `p` is at the light's position.
    #[inline]
    pub fn sample(&self, p: Vec3) -> Option<LightSample> {
        match *self {
            Light::Point { position, intensity } => {
                let v = position - p;
                let d2 = v.length_squared();
                if !(d2 > 0.0) {
                    return None;
                }
                let dist = d2.sqrt();
                Some(LightSample { wi: v / dist, dist, irradiance: intensity / d2 })
            }
            Light::Directional { direction, irradiance } => {
                Some(LightSample { wi: -direction, dist: f32::INFINITY, irradiance })
            }
        }
    }
}
