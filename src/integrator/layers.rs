//! Which `--layers` layer light belongs to, decided the same way in every integrator from the
//! lobes the camera path sampled (not from the materials it met), so the layers of the path
//! tracer, photon mapping and SPPM can be compared one by one.
//!
//! A bounce is *delta* when it sampled a mirror or glass lobe (even on a material that also has
//! a diffuse part); x is the first vertex left by a non-delta bounce, or the vertex where light
//! is gathered. Then:
//! - `SPECULAR`: the camera path bounced off mirrors or glass before x (E S+ ...);
//! - `DIRECT`: light emitted at the first hit, or reaching x straight from a light;
//! - `CAUSTIC`: light reaching x after one or more delta bounces only (L S+ x);
//! - `INDIRECT`: everything else (at least one more non-delta bounce after x).
//!
//! Light scattered in a participating medium is `INDIRECT` (`SPECULAR` when the camera path
//! reached the medium through mirrors or glass), single scattering from the lights included:
//! the photon integrators estimate a medium's light from volume photons of every kind at once,
//! and every integrator puts it in the same layer.

use crate::film::{CAUSTIC, DIRECT, INDIRECT, SPECULAR};

/// The state of a camera path for layer bookkeeping.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LayerPath {
    /// Delta bounces happened before any non-delta one.
    delta_prefix: bool,
    /// A non-delta bounce left x.
    left_x: bool,
    /// Bounces after the one that left x, and whether all of them were delta.
    after_x: u32,
    delta_since_x: bool,
    /// The path has scattered in a medium: all its light from there on is `other_photons`'.
    in_medium: bool,
}

impl Default for LayerPath {
    fn default() -> Self {
        Self::CAMERA
    }
}

impl LayerPath {
    /// A camera ray before its first bounce.
    pub const CAMERA: LayerPath =
        LayerPath { delta_prefix: false, left_x: false, after_x: 0, delta_since_x: true, in_medium: false };

    /// Records a bounce at the current vertex: `delta` when a mirror or glass lobe was sampled.
    pub fn bounce(&mut self, delta: bool) {
        if self.left_x {
            self.after_x += 1;
            self.delta_since_x &= delta;
        } else if delta {
            self.delta_prefix = true;
        } else {
            self.left_x = true;
        }
    }

    /// Records a scattering event in a medium (a non-delta bounce whose light, and all the
    /// path's light after it, is `other_photons`').
    pub fn scatter_in_medium(&mut self) {
        self.bounce(false);
        self.in_medium = true;
    }

    /// Whether the vertex the camera path reached is x or before it: every bounce so far was
    /// delta (`bdpt::mis`'s direct paths end at x).
    pub fn before_x(&self) -> bool {
        !self.left_x
    }

    /// Whether the vertex the camera path reached came straight after x: a non-delta bounce
    /// left x and nothing else since.
    pub fn just_left_x(&self) -> bool {
        self.left_x && self.after_x == 0
    }

    /// Whether a camera path in this state has bounced off a mirror or glass before x.
    pub fn delta_prefix(&self) -> bool {
        self.delta_prefix
    }

    /// The layer of light emitted at the vertex just reached (an emitter or the sky).
    pub fn emitted(&self) -> usize {
        if self.in_medium {
            self.other_photons()
        } else if self.delta_prefix {
            SPECULAR
        } else if !self.left_x || self.after_x == 0 {
            DIRECT
        } else if self.delta_since_x {
            CAUSTIC
        } else {
            INDIRECT
        }
    }

    /// The layer of light sampled from the lights at the vertex just reached.
    pub fn direct(&self) -> usize {
        if self.in_medium {
            self.other_photons()
        } else if self.delta_prefix {
            SPECULAR
        } else if self.left_x {
            INDIRECT
        } else {
            DIRECT
        }
    }

    /// The layer of caustic photons (those that came through mirrors and glass only) gathered
    /// at the vertex just reached.
    pub fn caustic_photons(&self) -> usize {
        if self.in_medium {
            self.other_photons()
        } else if self.delta_prefix {
            SPECULAR
        } else if self.left_x {
            INDIRECT
        } else {
            CAUSTIC
        }
    }

    /// The layer of every other photon (or final-gather ray) gathered at the vertex just reached.
    pub fn other_photons(&self) -> usize {
        if self.delta_prefix { SPECULAR } else { INDIRECT }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn camera_hits_are_direct_and_mirror_views_specular() {
        let mut p = LayerPath::CAMERA;
        assert_eq!(
            (p.emitted(), p.direct(), p.caustic_photons(), p.other_photons()),
            (DIRECT, DIRECT, CAUSTIC, INDIRECT)
        );
        p.bounce(true);
        assert_eq!(
            (p.emitted(), p.direct(), p.caustic_photons(), p.other_photons()),
            (SPECULAR, SPECULAR, SPECULAR, SPECULAR)
        );
        // Whatever follows a mirror prefix stays specular.
        p.bounce(false);
        p.bounce(false);
        assert_eq!((p.emitted(), p.direct()), (SPECULAR, SPECULAR));
    }

    #[test]
    fn light_scattered_in_a_medium_is_indirect_or_specular() {
        let mut p = LayerPath::CAMERA;
        p.scatter_in_medium();
        assert_eq!(
            (p.emitted(), p.direct(), p.caustic_photons(), p.other_photons()),
            (INDIRECT, INDIRECT, INDIRECT, INDIRECT)
        );
        // Still indirect after mirrors and surfaces beyond the medium vertex.
        p.bounce(true);
        p.bounce(false);
        assert_eq!((p.emitted(), p.direct()), (INDIRECT, INDIRECT));
        // Fog seen in a mirror is specular.
        let mut q = LayerPath::CAMERA;
        q.bounce(true);
        q.scatter_in_medium();
        assert_eq!((q.emitted(), q.direct(), q.other_photons()), (SPECULAR, SPECULAR, SPECULAR));
    }

    #[test]
    fn light_after_x_is_direct_caustic_or_indirect_by_the_bounces_since() {
        let mut p = LayerPath::CAMERA;
        p.bounce(false); // leaves x by a diffuse or glossy lobe
        assert_eq!((p.emitted(), p.direct()), (DIRECT, INDIRECT));
        let mut q = p;
        q.bounce(true); // a mirror after x
        q.bounce(true); // and glass
        assert_eq!((q.emitted(), q.direct(), q.caustic_photons()), (CAUSTIC, INDIRECT, INDIRECT));
        q.bounce(false);
        assert_eq!(q.emitted(), INDIRECT);
        p.bounce(false);
        assert_eq!((p.emitted(), p.other_photons()), (INDIRECT, INDIRECT));
    }
}
