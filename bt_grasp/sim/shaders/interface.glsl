// bt_grasp camera shader pack: the descriptor sets svulkan2 fills, declared by the names its renderer looks up.
// The block and member names below are svulkan2's interface (it matches them by name); the layout of each set
// is ours. No environment map and no BRDF lookup table are declared: without them svulkan2 builds no
// image-based-lighting resources, which on a CPU Vulkan driver saved seconds at the first picture.

struct DirectionalLight {
  vec4 direction;  // xyz: the direction the light travels, world frame
  vec4 emission;   // rgb: radiance
};

struct PointLight {
  vec4 position;   // xyz: world frame
  vec4 emission;   // rgb: intensity (falls off with the squared distance)
};

// Declared only because svulkan2 looks these up (spot and textured lights); the scenes have neither.
struct SpotLight {
  vec4 position;
  vec4 direction;
  vec4 emission;
};

// One shadow-casting light's view and projection (a point light has six, one per cube face).
struct LightView {
  mat4 viewMatrix;
  mat4 viewMatrixInverse;
  mat4 projectionMatrix;
  mat4 projectionMatrixInverse;
  int width;
  int height;
};

#ifdef WITH_CAMERA_SET
layout(set = 0, binding = 0) uniform CameraBuffer {
  mat4 viewMatrix;               // world -> camera (camera looks along -z, OpenGL style)
  mat4 projectionMatrix;
  mat4 viewMatrixInverse;
  mat4 projectionMatrixInverse;
  float width;
  float height;
} cameraBuffer;
#endif

#ifdef WITH_OBJECT_SET
layout(set = 1, binding = 0) uniform ObjectTransformBuffer {
  mat4 modelMatrix;              // object -> world
} objectTransformBuffer;

layout(set = 1, binding = 1) uniform ObjectDataBuffer {
  uvec4 segmentation;
  float transparency;
  int shadeFlat;                 // 1: facet normals from screen-space derivatives
} objectDataBuffer;
#endif

#ifdef WITH_MATERIAL_SET
layout(set = 2, binding = 0) uniform MaterialBuffer {
  vec4 emission;                 // rgb radiance, a: strength
  vec4 baseColor;
  float fresnel;                 // specular reflectance at normal incidence, in units of 0.08
  float roughness;
  float metallic;
  float transmission;
  float ior;
  float transmissionRoughness;
  int textureMask;               // bit 0 colour, 1 roughness, 2 normal, 3 metallic, 4 emission
  int padding1;
  vec4 textureTransforms[6];     // per texture: xy offset, zw scale of the uv
} materialBuffer;

layout(set = 2, binding = 1) uniform sampler2D colorTexture;
layout(set = 2, binding = 2) uniform sampler2D roughnessTexture;
layout(set = 2, binding = 3) uniform sampler2D normalTexture;
layout(set = 2, binding = 4) uniform sampler2D metallicTexture;
layout(set = 2, binding = 5) uniform sampler2D emissionTexture;
#endif

#if defined(WITH_SCENE_SET) || defined(WITH_SCENE_BUFFER)
#ifndef SCENE_SET
#define SCENE_SET 3
#endif
// How many lights of each kind the scene has (svulkan2 sets these when it builds a pipeline).
layout(constant_id = 0) const int NUM_DIRECTIONAL_LIGHTS = 3;
layout(constant_id = 1) const int NUM_POINT_LIGHTS = 10;
layout(constant_id = 2) const int NUM_DIRECTIONAL_LIGHT_SHADOWS = 1;
layout(constant_id = 3) const int NUM_POINT_LIGHT_SHADOWS = 3;
layout(constant_id = 4) const int NUM_SPOT_LIGHTS = 1;             // unused (see SpotLight)
layout(constant_id = 5) const int NUM_SPOT_LIGHT_SHADOWS = 1;
layout(constant_id = 6) const int NUM_TEXTURED_LIGHT_SHADOWS = 1;
// Shadow-casting lights come first in each array (svulkan2's order): directional light 0 and point lights
// 0..2 may cast shadows, as in SAPIEN's default pack.
layout(set = SCENE_SET, binding = 0) uniform SceneBuffer {
  vec4 ambientLight;
  DirectionalLight directionalLights[3];
  PointLight pointLights[10];
  SpotLight spotLights[1];
  SpotLight texturedLights[1];
} sceneBuffer;
#endif

#ifdef WITH_SCENE_SET

layout(set = SCENE_SET, binding = 1) uniform ShadowBuffer {
  LightView directionalLightBuffers[1];
  LightView pointLightBuffers[18];  // six cube faces per shadow-casting point light
  LightView spotLightBuffers[1];    // unused (see SpotLight)
  LightView texturedLightBuffers[1];
} shadowBuffer;

layout(set = SCENE_SET, binding = 2) uniform sampler2D samplerDirectionalLightDepths[1];
layout(set = SCENE_SET, binding = 3) uniform samplerCube samplerPointLightDepths[3];
layout(set = SCENE_SET, binding = 4) uniform sampler2D samplerSpotLightDepths[1];      // unused (see SpotLight)
layout(set = SCENE_SET, binding = 5) uniform sampler2D samplerTexturedLightDepths[1];
layout(set = SCENE_SET, binding = 6) uniform sampler2D samplerTexturedLightTextures[1];
#endif
