// The point-light caustic Cornell box of scenes/13-cornell-caustics.toml, for POV-Ray 3.7:
// the same walls, mirror sphere, glass sphere and point light, in linear units so its HDR
// output compares pixel for pixel with caustic's EXR (scripts/povray_compare.py).
//
// Matching caustic's scene:
// - caustic is right-handed (x to the left seen from the camera); POV-Ray is left-handed, so the
//   camera's `right` vector is -x.
// - caustic's camera: pinhole at (2.78, 2.73, -8) looking along +z, 39.3 degrees field of view
//   on a square image (POV-Ray's `angle` is the horizontal one; equal here).
// - caustic's point light has intensity I = 12 W/sr and falls off as 1/r^2; a Lambertian wall
//   of albedo rho shows L = rho I cos / (pi r^2). POV-Ray shows rho * C * cos * fade with
//   fade = 2 / (1 + (r/D)^2) under `fade_power 2`, about 2 D^2 / r^2 for r >> D. With D = 0.001
//   and C = I / (2 pi D^2) the two agree to 1e-5 relative at the walls' distances.
// - `diffuse 1`, `ambient 0`, `emission 0`: POV-Ray's default diffuse is 0.6.
// - `assumed_gamma 1.0` and HDR output (+FH): linear values throughout.
// - Mirror: reflectance 0.95, nothing diffuse. Glass: ior 1.5, Fresnel reflection and the
//   rest transmitted (conserve_energy), clear.

#version 3.7;

global_settings {
  assumed_gamma 1.0
  max_trace_level 11
  photons {
    count 200000
    autostop 0
    jitter 0.4
    max_trace_level 11
    media 0
  }
  radiosity {
    pretrace_start 0.08
    pretrace_end 0.01
    count 200
    nearest_count 10
    error_bound 0.5
    recursion_limit 3
    low_error_factor 0.5
    gray_threshold 0.0
    minimum_reuse 0.015
    brightness 1.0
    adc_bailout 0.005
    always_sample off
  }
}

#declare Diffuse = finish { ambient 0 emission 0 diffuse 1 specular 0 phong 0 }

camera {
  perspective
  location <2.78, 2.73, -8.0>
  look_at <2.78, 2.73, 0.0>
  right -x
  up y
  angle 39.3
}

#declare Intensity = 12;
#declare FadeD = 0.001;
light_source {
  <2.78, 5.0, 2.8>
  color rgb Intensity / (2 * pi * FadeD * FadeD)
  fade_distance FadeD
  fade_power 2
  photons { refraction on reflection on }
}

#declare White = texture { pigment { rgb <0.73, 0.73, 0.73> } finish { Diffuse } }
#declare Red = texture { pigment { rgb <0.65, 0.05, 0.05> } finish { Diffuse } }
#declare Green = texture { pigment { rgb <0.12, 0.45, 0.15> } finish { Diffuse } }

// Floor, ceiling, back wall, left (red, x = 5.56) and right (green, x = 0) walls.
polygon { 5, <0, 0, 0>, <5.56, 0, 0>, <5.56, 0, 5.592>, <0, 0, 5.592>, <0, 0, 0> texture { White } }
polygon { 5, <0, 5.488, 0>, <5.56, 5.488, 0>, <5.56, 5.488, 5.592>, <0, 5.488, 5.592>, <0, 5.488, 0> texture { White } }
polygon { 5, <0, 0, 5.592>, <5.56, 0, 5.592>, <5.56, 5.488, 5.592>, <0, 5.488, 5.592>, <0, 0, 5.592> texture { White } }
polygon { 5, <5.56, 0, 0>, <5.56, 0, 5.592>, <5.56, 5.488, 5.592>, <5.56, 5.488, 0>, <5.56, 0, 0> texture { Red } }
polygon { 5, <0, 0, 0>, <0, 0, 5.592>, <0, 5.488, 5.592>, <0, 5.488, 0>, <0, 0, 0> texture { Green } }

// Mirror sphere (back left).
sphere {
  <3.7, 1.0, 3.6>, 1.0
  texture { pigment { rgb 0 } finish { ambient 0 emission 0 diffuse 0 specular 0 reflection 0.95 } }
  photons { target reflection on refraction off collect off }
}

// Glass sphere (front right).
sphere {
  <1.9, 1.0, 1.7>, 1.0
  texture {
    pigment { rgbf <1, 1, 1, 1> }
    finish { ambient 0 emission 0 diffuse 0 specular 0 reflection { 0, 1 fresnel on } conserve_energy }
  }
  interior { ior 1.5 }
  photons { target reflection on refraction on collect off }
}
