// benches/scenes/whitted-lights.toml for POV-Ray 3.7 (timing comparison in
// scripts/povray_whitted.sh): four coloured point lights, rectangles for the floor and two walls,
// a red box and a mirror box, chrome, glass and yellow Phong spheres; 512 x 512, 16 samples per
// pixel, trace depth as caustic's max_depth.
// Render with: povray +Iwhitted-lights.pov +W512 +H512 +A0.0 +AM1 +R4 -J +FN +Ooutput.png
#version 3.7;
global_settings { assumed_gamma 1.0 max_trace_level 5 ambient_light rgb 1 }
background { rgb <0.05, 0.05, 0.1> }
camera {
  perspective
  location <0.5, 2.2, 7>
  look_at <0, 0.8, 0>
  right x
  up y
  angle 50
}
light_source { <4, 5, 4> rgb 30 * <1, 0.9, 0.8> fade_distance 1 fade_power 2 }
light_source { <-4, 4, 3> rgb 20 * <0.7, 0.8, 1> fade_distance 1 fade_power 2 }
light_source { <0, 6, -1> rgb 15 fade_distance 1 fade_power 2 }
light_source { <2, 1.5, 5> rgb 6 * <1, 0.6, 0.4> fade_distance 1 fade_power 2 }
#declare Wall = finish { ambient 0.05 diffuse 1 }
polygon { 5, <-5, 0, -3>, <-5, 0, 6>, <5, 0, 6>, <5, 0, -3>, <-5, 0, -3>
  pigment { rgb <0.75, 0.75, 0.7> } finish { Wall } }
polygon { 5, <-5, 0, -3>, <5, 0, -3>, <5, 5, -3>, <-5, 5, -3>, <-5, 0, -3>
  pigment { rgb <0.6, 0.65, 0.7> } finish { Wall } }
polygon { 5, <-5, 0, -3>, <-5, 5, -3>, <-5, 5, 6>, <-5, 0, 6>, <-5, 0, -3>
  pigment { rgb <0.6, 0.65, 0.7> } finish { Wall } }
box { <-0.5, 0, -0.5>, <0.5, 1, 0.5>
  rotate y * 30 translate <-2.2, 0, -0.8>
  pigment { rgb <0.8, 0.15, 0.1> }
  finish { ambient 0.05 diffuse 1 phong 0.2 }
}
box { <-0.6, 0, -0.3>, <0.6, 1.8, 0.3>
  rotate y * -20 translate <1.8, 0, -1.8>
  pigment { rgb <0.8, 0.85, 0.9> }
  finish { ambient 0.05 diffuse 0.1 phong 0.5 phong_size 80 reflection { 0.7 } }
}
sphere { <-0.6, 0.8, 0.4>, 0.8
  pigment { rgb <0.95, 0.95, 0.95> }
  finish { ambient 0.05 diffuse 0.05 phong 0.8 phong_size 200 reflection { 0.85 } }
}
#declare Glass = material {
  texture {
    pigment { rgbf <1, 1, 1, 1> }
    finish { ambient 0 diffuse 0 phong 0.5 phong_size 200 reflection { 0 1 fresnel on } conserve_energy }
  }
  interior { ior 1.5 }
}
sphere { <1.0, 0.6, 1.2>, 0.6 material { Glass } }
sphere { <0.3, 0.3, 2.4>, 0.3 material { Glass } }
sphere { <-2.2, 1.4, -0.8>, 0.4
  pigment { rgb <0.9, 0.8, 0.2> }
  finish { ambient 0.05 diffuse 1 phong 0.5 phong_size 40 }
}
