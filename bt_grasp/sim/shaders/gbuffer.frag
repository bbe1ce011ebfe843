#version 450
// bt_grasp camera shader pack, the one (forward) pass: material, direct lighting (ambient, directional and
// point lights, their shadow maps when a light casts shadows), display gamma. Writes the lit colour and the
// camera-frame position; composite0.frag turns them into the pictures the pipeline reads. Both carry alpha 1:
// svulkan2 blends what a gbuffer pass writes by its alpha. No image-based lighting.

#define WITH_CAMERA_SET
#define WITH_OBJECT_SET
#define WITH_MATERIAL_SET
#define WITH_SCENE_SET
#include "./interface.glsl"
#include "./shading.glsl"

layout(location = 0) in vec4 vCameraPosition;
layout(location = 1) in vec2 vUV;
layout(location = 2) in vec3 vNormal;
layout(location = 3) in vec3 vTangent;
layout(location = 4) in vec3 vBitangent;

layout(location = 0) out vec4 outLit;
layout(location = 1) out vec4 outPositionRaw;

bool hasTexture(int bit) {
  return (materialBuffer.textureMask & (1 << bit)) != 0;
}

vec4 sampleMaterial(sampler2D map, int slot) {
  vec4 t = materialBuffer.textureTransforms[slot];
  return texture(map, vUV * t.zw + t.xy);
}

void main() {
  vec4 base = hasTexture(0) ? sampleMaterial(colorTexture, 0) : materialBuffer.baseColor;
  if (base.a == 0.0) {
    discard;
  }
  float roughness = hasTexture(1) ? sampleMaterial(roughnessTexture, 1).r : materialBuffer.roughness;
  float metallic = hasTexture(3) ? sampleMaterial(metallicTexture, 3).r : materialBuffer.metallic;
  vec4 emission = materialBuffer.emission;
  if (hasTexture(4)) {
    emission.rgb *= sampleMaterial(emissionTexture, 4).rgb;
  }

  vec3 p = vCameraPosition.xyz / vCameraPosition.w;
  vec3 n;
  if (objectDataBuffer.shadeFlat != 0) {
    n = normalize(cross(dFdy(p), dFdx(p)));
  } else if (hasTexture(2)) {
    vec3 m = sampleMaterial(normalTexture, 2).xyz * 2.0 - 1.0;
    n = normalize(mat3(vTangent, vBitangent, vNormal) * m);
  } else {
    n = normalize(vNormal);
  }
  n = dot(n, p) < 0.0 ? n : -n;  // the side facing the camera

  Surface s;
  s.n = n;
  s.v = -normalize(p);
  s.diffuse = base.rgb * (1.0 - metallic);
  s.f0 = vec3(materialBuffer.fresnel * 0.08 * (1.0 - metallic)) + base.rgb * metallic;
  s.roughness = roughness;

  mat3 worldToCamera = mat3(cameraBuffer.viewMatrix);
  vec3 worldPos = (cameraBuffer.viewMatrixInverse * vec4(p, 1.0)).xyz;
  vec3 radiance = emission.rgb * emission.a + sceneBuffer.ambientLight.rgb * base.rgb;

  for (int i = 0; i < NUM_DIRECTIONAL_LIGHTS; ++i) {
    vec3 l = -(worldToCamera * sceneBuffer.directionalLights[i].direction.xyz);
    float visible = 1.0;
    if (i < NUM_DIRECTIONAL_LIGHT_SHADOWS) {
      visible = directionalVisibility(samplerDirectionalLightDepths[i], shadowBuffer.directionalLightBuffers[i],
                                      worldPos);
    }
    radiance += visible * reflectLight(s, l, sceneBuffer.directionalLights[i].emission.rgb);
  }

  for (int i = 0; i < NUM_POINT_LIGHTS; ++i) {
    vec3 toLight = (cameraBuffer.viewMatrix * vec4(sceneBuffer.pointLights[i].position.xyz, 1.0)).xyz - p;
    float d = length(toLight);
    if (d == 0.0) {
      continue;
    }
    float visible = 1.0;
    if (i < NUM_POINT_LIGHT_SHADOWS) {
      visible = pointVisibility(samplerPointLightDepths[i], shadowBuffer.pointLightBuffers[6 * i],
                                sceneBuffer.pointLights[i].position.xyz - worldPos);
    }
    radiance += visible * reflectLight(s, toLight / d, sceneBuffer.pointLights[i].emission.rgb / (d * d));
  }

  outLit = vec4(clamp(pow(radiance, vec3(1.0 / 2.2)), 0.0, 1.0), 1.0);
  outPositionRaw = vec4(vCameraPosition.xyz, 1.0);
}
