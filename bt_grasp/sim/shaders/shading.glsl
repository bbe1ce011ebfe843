// bt_grasp camera shader pack: the reflectance model. A Lambertian diffuse lobe plus the microfacet specular
// lobe of Karis, "Real Shading in Unreal Engine 4" (SIGGRAPH 2013 course notes): GGX distribution,
// Schlick-Smith visibility with k = (roughness + 1)^2 / 8, and Schlick's Fresnel term with the spherical-
// Gaussian exponent. SAPIEN's own packs use the same model, so pictures match theirs (docs/rendering.md).

const float PI = 3.141592653589793;

struct Surface {
  vec3 n;          // unit normal, camera frame, facing the viewer
  vec3 v;          // unit direction to the viewer, camera frame
  vec3 diffuse;    // diffuse albedo (base colour without the metallic part)
  vec3 f0;         // specular reflectance at normal incidence
  float roughness;
};

// Radiance reflected towards the viewer from light arriving along unit direction `l` (towards the light)
// with irradiance-scale `e`.
vec3 reflectLight(Surface s, vec3 l, vec3 e) {
  float nDotL = clamp(dot(s.n, l), 0.0, 1.0);
  vec3 halfway = l + s.v;
  halfway = dot(halfway, halfway) < 1e-6 ? vec3(0.0) : normalize(halfway);
  float nDotH = clamp(dot(s.n, halfway), 1e-6, 1.0);
  float vDotH = clamp(dot(s.v, halfway), 1e-6, 1.0);
  float nDotV = clamp(dot(s.n, s.v), 1e-6, 1.0);

  float a = s.roughness * s.roughness;
  float a2 = a * a;
  float k = (s.roughness + 1.0) * (s.roughness + 1.0) / 8.0;
  vec3 fresnel = s.f0 + (1.0 - s.f0) * exp2((-5.55473 * vDotH - 6.98316) * vDotH);
  float lobe = nDotH * nDotH * (a2 - 1.0) + 1.0;
  float denominator = 4.0 * PI * lobe * lobe * (nDotV * (1.0 - k) + k) * (nDotL * (1.0 - k) + k);
  vec3 specular = fresnel * a2 / clamp(denominator, 1e-6, 4.0 * PI);

  return e * (s.diffuse * nDotL / PI + specular * nDotL);
}

// Fraction of a directional light's shadow map that does not occlude `worldPos`: a 5x5 percentage-closer
// filter over bilinearly weighted texel quads.
float directionalVisibility(sampler2D depths, LightView light, vec3 worldPos) {
  vec4 clip = light.projectionMatrix * light.viewMatrix * vec4(worldPos, 1.0);
  vec3 coord = clip.xyz / clip.w;
  coord.xy = coord.xy * 0.5 + 0.5;
  float size = float(textureSize(depths, 0).x);
  vec2 weight = fract(coord.xy * size + 0.5);
  float lit = 0.0;
  for (int dy = -2; dy <= 2; ++dy) {
    for (int dx = -2; dx <= 2; ++dx) {
      vec4 d = textureGather(depths, coord.xy + vec2(dx, dy) / size);
      vec4 open = vec4(greaterThanEqual(d, vec4(coord.z)));
      lit += mix(mix(open.w, open.z, weight.x), mix(open.x, open.y, weight.x), weight.y);
    }
  }
  return lit / 25.0;
}

// 1 when a point light reaches `worldPos` (`toLight`: world-frame vector from the point to the light), else 0.
float pointVisibility(samplerCube depths, LightView face, vec3 toLight) {
  vec3 a = abs(toLight);
  vec4 clip = face.projectionMatrix * vec4(0.0, 0.0, -max(max(a.x, a.y), a.z), 1.0);
  float pixelDepth = clip.z / clip.w;
  return pixelDepth <= texture(depths, toLight).x ? 1.0 : 0.0;
}
