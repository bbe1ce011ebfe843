#version 450
// bt_grasp camera shader pack, the full-screen pass: the pictures the pipeline reads.
//   Color:    the lit colour; where nothing was drawn, the ambient light (gamma-encoded, alpha 0).
//   Position: camera-frame xyz in metres and, in w, the depth-buffer value (1 where nothing was drawn).
layout(set = 0, binding = 0) uniform sampler2D samplerLit;
layout(set = 0, binding = 1) uniform sampler2D samplerPositionRaw;
layout(set = 0, binding = 2) uniform sampler2D samplerGbufferDepth;

#define WITH_SCENE_BUFFER
#define SCENE_SET 1
#include "./interface.glsl"

layout(location = 0) in vec2 vUV;

layout(location = 0) out vec4 outColor;
layout(location = 1) out vec4 outPosition;

void main() {
  float depth = texture(samplerGbufferDepth, vUV).x;
  if (depth < 1.0) {
    outColor = texture(samplerLit, vUV);
  } else {
    outColor = vec4(clamp(pow(sceneBuffer.ambientLight.rgb, vec3(1.0 / 2.2)), 0.0, 1.0), 0.0);
  }
  outPosition = vec4(texture(samplerPositionRaw, vUV).xyz, depth);
}
