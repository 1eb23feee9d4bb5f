// benches/scenes/whitted-rects.toml for POV-Ray 3.7 (timing comparison in
// scripts/povray_whitted.sh): a mirror sphere and a Fresnel glass sphere over two rectangles,
// two point lights, 512 x 512, 16 samples per pixel, trace depth as caustic's max_depth.
// Render with: povray +Iwhitted-rects.pov +W512 +H512 +A0.0 +AM1 +R4 -J +FN +Ooutput.png
#version 3.7;
global_settings { assumed_gamma 1.0 max_trace_level 5 ambient_light rgb 1 }
background { rgb <0.3, 0.5, 0.8> }
camera {
  perspective
  location <0, 1.6, 6.5>
  look_at <0, 0.9, 0>
  right x
  up y
  angle 45
}
// Point lights with inverse-square fall-off, as caustic's.
light_source { <3, 5, 4> rgb 40 fade_distance 1 fade_power 2 }
light_source { <-3, 4, 5> rgb 25 fade_distance 1 fade_power 2 }
polygon { 5, <-4, 0, -3>, <-4, 0, 5>, <4, 0, 5>, <4, 0, -3>, <-4, 0, -3>
  pigment { rgb <0.8, 0.8, 0.75> }
  finish { ambient 0.1 diffuse 1 }
}
polygon { 5, <-4, 0, -3>, <4, 0, -3>, <4, 5, -3>, <-4, 5, -3>, <-4, 0, -3>
  pigment { rgb <0.7, 0.75, 0.8> }
  finish { ambient 0.1 diffuse 1 }
}
sphere { <-1.1, 1, -0.6>, 1
  pigment { rgb <0.9, 0.9, 0.9> }
  finish { ambient 0.1 diffuse 0.1 phong 0.6 phong_size 100 reflection { 0.8 } }
}
sphere { <1.2, 0.8, 0.6>, 0.8
  pigment { rgbf <1, 1, 1, 1> }
  finish { ambient 0 diffuse 0 phong 0.5 phong_size 200 reflection { 0 1 fresnel on } conserve_energy }
  interior { ior 1.5 }
}
