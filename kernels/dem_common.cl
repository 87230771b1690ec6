// Helpers used by several DEM kernels: grid cells, contact geometry, Hertz stiffness.

// grid cell of a point, clamped into the grid (clamping merges outer cells, never splits them,
// so no pair within one cell size is missed)
int3 cell_of(float3 x, const TlStepParams p) {
  // the lattice cell (from the bounds' corner: the same float operations with a grid region or
  // without), then the grid's own index, clamped into it
  float3 rel = (x - p.grid_origin.xyz) / p.cell_size;
  int3 c = convert_int3_rtn(rel) - (int3)(p.grid_i0, p.grid_j0, p.grid_k0);
  return clamp(c, (int3)(0, 0, 0), (int3)(p.grid_nx - 1, p.grid_ny - 1, p.grid_nz - 1));
}

int cell_index(int3 c, const TlStepParams p) {
  return (c.z * p.grid_ny + c.y) * p.grid_nx + c.x;
}

// Hertz normal stiffness k_n = 4/3 E* sqrt(R*) with 1/E* = 2 (1 - nu^2) / E (one material)
float hertz_stiffness(float reduced_radius, const TlStepParams p) {
  float e_star = p.young / (2.0f * (1.0f - p.poisson * p.poisson));
  return (4.0f / 3.0f) * e_star * sqrt(reduced_radius);
}

// sphere a (x, r) against static geometry g: unit normal from the sphere into g and the gap.
// A box whose surface lies farther than r + reach from x gives INFINITY and no normal: rejected
// on the squared distance, before the root, the division and the normal (the narrow phase's
// count pass, where most of a voxel column's boxes are out of reach; issue 14). The 1e-4 slack
// is far above float rounding, so every box within r + reach gets its gap and normal as
// sphere_geom computes them: the same bits
float sphere_geom_within(float3 x, float r, __global const TlGeom* g, float reach, float3* normal) {
  float3 c = g->centre.xyz;
  if (g->type == TL_GEOM_PLANE) {
    float3 m = g->axis_x.xyz;
    *normal = -m;
    return dot(x - c, m) - r;
  }
  // box: closest point in the box frame
  float3 d = x - c;
  float3 p_box = (float3)(dot(d, g->axis_x.xyz), dot(d, g->axis_y.xyz), dot(d, g->axis_z.xyz));
  float3 h = g->half_extent.xyz;
  float3 q = clamp(p_box, -h, h);
  float3 diff = p_box - q;
  float dist2 = dot(diff, diff);
  if (dist2 > 1.0001f * (r + reach) * (r + reach)) return INFINITY;
  if (dist2 > 0.0f) {
    float dist = sqrt(dist2);
    float3 nl = -diff / dist;
    *normal = nl.x * g->axis_x.xyz + nl.y * g->axis_y.xyz + nl.z * g->axis_z.xyz;
    return dist - r;
  }
  // centre inside: leave through the nearest face
  float3 depth = h - fabs(p_box);
  int k = depth.x <= depth.y ? (depth.x <= depth.z ? 0 : 2) : (depth.y <= depth.z ? 1 : 2);
  float3 axis = k == 0 ? g->axis_x.xyz : (k == 1 ? g->axis_y.xyz : g->axis_z.xyz);
  float s = (k == 0 ? p_box.x : (k == 1 ? p_box.y : p_box.z)) >= 0.0f ? 1.0f : -1.0f;
  *normal = -s * axis;
  float dk = k == 0 ? depth.x : (k == 1 ? depth.y : depth.z);
  return -dk - r;
}

// sphere a (x, r) against static geometry g, whatever the distance
float sphere_geom(float3 x, float r, __global const TlGeom* g, float3* normal) {
  return sphere_geom_within(x, r, g, INFINITY, normal);
}

// a bijective 32-bit mix: distinct contacts get distinct colouring priorities
uint contact_priority(uint c) {
  c ^= c >> 16;
  c *= 0x7feb352du;
  c ^= c >> 15;
  c *= 0x846ca68bu;
  c ^= c >> 16;
  return c;
}
