#!/bin/sh
# Regenerates the texture fixtures with ImageMagick 6 and libjpeg-turbo's cjpeg (Debian:
# `apt-get install imagemagick libjpeg-turbo-progs`): files from encoders other than ours, read
# back by `texture::image` tests. Sources are two plain PPMs with known values.
set -e
cd "$(dirname "$0")"
# 5 x 4: odd width (row padding), every texel different; row 0 (top) is reddish.
printf 'P3\n5 4\n255\n' > src5x4.ppm
for y in 0 1 2 3; do for x in 0 1 2 3 4; do
  printf '%d %d %d\n' $((200 - 40 * y + x)) $((10 + 50 * x)) $((30 + 60 * y)) >> src5x4.ppm
done; done
# 16 x 16 JPEG source: top half (200, 40, 40), bottom half (30, 60, 220), in 8 x 8 blocks.
printf 'P3\n16 16\n255\n' > src16.ppm
for y in $(seq 0 15); do for x in $(seq 0 15); do
  if [ $y -lt 8 ]; then echo '200 40 40'; else echo '30 60 220'; fi >> src16.ppm
done; done
convert src5x4.ppm -interlace PNG interlaced.png
convert src5x4.ppm -define bmp:format=bmp3 -type truecolor bmp3-24.bmp
convert src5x4.ppm -define bmp:format=bmp4 -type truecolormatte bmp4-32.bmp
convert src5x4.ppm -compress RLE rle.tga
convert src5x4.ppm -depth 16 -define quantum:format=floating-point im.pfm
convert src5x4.ppm im.hdr
convert src5x4.ppm im.exr
cjpeg -quality 100 -sample 1x1 src16.ppm > baseline.jpg
cjpeg -quality 100 -sample 1x1 -progressive src16.ppm > progressive.jpg
cjpeg -quality 100 -grayscale src16.ppm > grey.jpg
rm src5x4.ppm src16.ppm
