#version 450
// bt_grasp camera shader pack: one triangle that covers the screen, for the full-screen pass.
layout(location = 0) out vec2 vUV;

void main() {
  // vertices 0, 1, 2 -> uv (0, 0), (2, 0), (0, 2): the triangle's inside covers [0, 1]^2
  vUV = vec2(float((gl_VertexIndex & 1) << 1), float(gl_VertexIndex & 2));
  gl_Position = vec4(vUV * 2.0 - 1.0, 0.0, 1.0);
}
