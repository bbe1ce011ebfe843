#version 450
// bt_grasp camera shader pack, the one (forward) pass: vertices to the camera frame.
#define WITH_CAMERA_SET
#define WITH_OBJECT_SET
#include "./interface.glsl"

layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec2 uv;
layout(location = 3) in vec3 tangent;
layout(location = 4) in vec3 bitangent;

layout(location = 0) out vec4 vCameraPosition;
layout(location = 1) out vec2 vUV;
layout(location = 2) out vec3 vNormal;
layout(location = 3) out vec3 vTangent;
layout(location = 4) out vec3 vBitangent;

void main() {
  mat4 modelView = cameraBuffer.viewMatrix * objectTransformBuffer.modelMatrix;
  vCameraPosition = modelView * vec4(position, 1);
  gl_Position = cameraBuffer.projectionMatrix * vCameraPosition;
  vUV = uv;

  // normals transform with the inverse transpose; a mesh without tangents gets any frame around its normal
  mat3 normalMatrix = transpose(inverse(mat3(modelView)));
  vec3 t = tangent;
  vec3 b = bitangent;
  if (length(t) < 0.01 || length(b) < 0.01) {
    vec3 seed = abs(normal.x) > 0.95 ? vec3(0, 1, 0) : vec3(1, 0, 0);
    b = normalize(cross(normal, seed));
    t = cross(b, normal);
  }
  vNormal = normalize(normalMatrix * normal);
  vTangent = normalize(normalMatrix * t);
  vBitangent = normalize(normalMatrix * b);
}
