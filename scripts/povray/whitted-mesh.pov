// benches/scenes/whitted-mesh.toml for POV-Ray 3.7 (timing comparison in
// scripts/povray_whitted.sh): the 5,120-triangle blob of scenes/meshes/blob.ply (as a mesh2 in
// blob.inc, written by scripts/ply_to_pov.py) beside a mirror sphere and a Fresnel glass sphere on
// a rectangle floor, two point lights; 512 x 512, 16 samples per pixel, trace depth 5.
// Render with: povray +Iwhitted-mesh.pov +W512 +H512 +A0.0 +AM1 +R4 -J +FN +Ooutput.png
#version 3.7;
global_settings { assumed_gamma 1.0 max_trace_level 5 ambient_light rgb 1 }
background { rgb <0.3, 0.5, 0.8> }
camera {
  perspective
  location <0, 1.4, 5>
  look_at <0, 0.6, 0>
  right x
  up y
  angle 45
}
light_source { <3, 5, 4> rgb 40 fade_distance 1 fade_power 2 }
light_source { <-3, 4, 5> rgb 25 fade_distance 1 fade_power 2 }
polygon { 5, <-4, 0, -4>, <-4, 0, 4>, <4, 0, 4>, <4, 0, -4>, <-4, 0, -4>
  pigment { rgb <0.8, 0.8, 0.75> }
  finish { ambient 0.1 diffuse 1 }
}
#include "blob.inc"
object { Blob
  scale 12 translate <0, 0, -0.3>
  pigment { rgb <0.75, 0.45, 0.3> }
  finish { ambient 0.1 diffuse 1 phong 0.4 phong_size 30 }
}
sphere { <-1.5, 0.7, 0.2>, 0.7
  pigment { rgb <0.9, 0.9, 0.9> }
  finish { ambient 0.1 diffuse 0.1 phong 0.6 phong_size 100 reflection { 0.8 } }
}
sphere { <1.4, 0.6, 0.6>, 0.6
  pigment { rgbf <1, 1, 1, 1> }
  finish { ambient 0 diffuse 0 phong 0.5 phong_size 200 reflection { 0 1 fresnel on } conserve_energy }
  interior { ior 1.5 }
}
