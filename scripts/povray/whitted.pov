// The Whitted benchmark scene of benches/scenes/whitted.toml for POV-Ray 3.7 (timing comparison
// in scripts/povray_whitted.sh): a floor plane, a mirror sphere, a Fresnel glass sphere and a red
// sphere under two point lights, 512 x 512, 16 samples per pixel, trace depth as caustic's
// max_depth. Render with: povray +Iwhitted.pov +W512 +H512 +A0.0 +AM1 +R4 -J +FN +Ooutput.png
#version 3.7;
global_settings { assumed_gamma 1.0 max_trace_level 6 ambient_light rgb 1 }
background { rgb <0.3, 0.5, 0.8> }
camera {
  perspective
  location <0, 1.5, 6>
  look_at <0, 0.8, 0>
  right x
  up y
  angle 45
}
// Point lights with inverse-square fall-off, as caustic's.
light_source { <4, 6, 5> rgb 50 fade_distance 1 fade_power 2 }
light_source { <-4, 5, 3> rgb 30 fade_distance 1 fade_power 2 }
plane { y, 0
  pigment { rgb <0.8, 0.8, 0.75> }
  finish { ambient 0.1 diffuse 1 }
}
sphere { <-1.3, 1, -0.5>, 1
  pigment { rgb <0.9, 0.9, 0.9> }
  finish { ambient 0.1 diffuse 0.1 phong 0.6 phong_size 100 reflection { 0.8 } }
}
sphere { <1.2, 0.9, 0.5>, 0.9
  pigment { rgbf <1, 1, 1, 1> }
  finish { ambient 0 diffuse 0 phong 0.5 phong_size 200 reflection { 0 1 fresnel on } conserve_energy }
  interior { ior 1.5 }
}
sphere { <0.3, 0.5, -2.5>, 0.5
  pigment { rgb <0.8, 0.2, 0.2> }
  finish { ambient 0.1 diffuse 1 phong 0.3 }
}
