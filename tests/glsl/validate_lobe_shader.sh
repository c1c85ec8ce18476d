#!/usr/bin/env bash
# Compiles the ndfbake.glsl a bake writes as the engines it is for would: GLSL 3.30 core, GLSL ES
# 3.00 (WebGL 2, where a float needs a precision) and Vulkan GLSL 4.50 to SPIR-V, each with a
# fragment shader that calls every function it offers, for half and for float textures.
# Usage: validate_lobe_shader.sh NDFBAKE_CLI GLSLANG_VALIDATOR
set -euo pipefail
ndfbake=$1 glslang=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
"$ndfbake" synth fbm --size 16 --out "$work/map.png" >/dev/null
calls='vec4 t[NDFB_LOBES];
for (int j = 0; j < NDFB_LOBES; ++j) t[j] = texture(lobes, uv);
NdfbLobe lobe = ndfb_lobe(t[0], 0.1);
color = vec4(ndfb_ggx_specular(t, 0.1, vec3(0.04), vec3(0.0, 0.0, 1.0), normalize(vec3(0.3, 0.0, 1.0))),
             ndfb_filtered_ggx_d(t, 0.1, lobe.normal) + ndfb_lambert_cosine(t, vec3(0.0, 0.0, 1.0)) + lobe.alpha);'
for precision in half float; do
  "$ndfbake" bake "$work/map.png" --out "$work/$precision" --precision "$precision" --max-lobes 3 --quiet >/dev/null
  shader="$work/$precision/ndfbake.glsl"
  grep -q "#define NDFB_LOBES 3" "$shader"
  for version in "330" "300 es" "450"; do
    file="$work/${precision}_${version// /}.frag"
    { echo "#version $version"
      cat "$shader"
      if [ "$version" = 450 ]; then
        echo "layout(location = 0) in vec2 uv; layout(binding = 0) uniform sampler2D lobes;"
        echo "layout(location = 0) out vec4 color;"
      else
        echo "in vec2 uv; uniform sampler2D lobes; out vec4 color;"
      fi
      echo "void main() { $calls }"; } > "$file"
    if [ "$version" = 450 ]; then "$glslang" -V "$file" -o "$work/out.spv" >/dev/null
    else "$glslang" "$file" >/dev/null; fi
    echo "ndfbake.glsl ($precision textures) compiles as GLSL $version"
  done
done
