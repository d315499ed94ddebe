// overlay.glsl — geometry of the BVH overlay pass (report §3.3): the 24 line vertices of a box and
// the projection that matches the tracer's camera, so a line and a traced surface at the same
// place land on the same pixel. Shared by overlay.vert and the CPU reference's line rasterizer.

/// Corner (bit 0: x, bit 1: y, bit 2: z; 0 = lo, 1 = hi) of line vertex 0..23: vertex pairs are
/// the 12 edges, four along each axis.
uint box_corner(uint vertex) {
    uint edge = vertex / 2u;
    uint axis = edge / 4u;
    uint k = edge % 4u;
    uint a1 = (axis + 1u) % 3u;
    uint a2 = (axis + 2u) % 3u;
    return ((vertex % 2u) << axis) | ((k & 1u) << a1) | ((k >> 1u) << a2);
}

vec3 corner_position(vec3 lo, vec3 hi, uint corner) {
    return vec3((corner & 1u) != 0u ? hi.x : lo.x, (corner & 2u) != 0u ? hi.y : lo.y, (corner & 4u) != 0u ? hi.z : lo.z);
}

/// Clip-space position under the tracer's pinhole camera (camera_ray_dir in shade.glsl, with its
/// shifted image plane), Vulkan conventions: y down, depth 0 at the near plane (overlay_near) and 1
/// at the far plane (overlay_far).
vec4 overlay_clip(vec3 p) {
    vec3 v = p - frame.camera_position;
    float x = dot(v, frame.camera_right);
    float y = dot(v, frame.camera_up);
    float z = dot(v, frame.camera_forward);
    float near = frame.overlay_near;
    float far = frame.overlay_far;
    return vec4((x - frame.shift_x * z) / (frame.tan_half_fov_y * frame.aspect),
                (frame.shift_y * z - y) / frame.tan_half_fov_y, far / (far - near) * (z - near), z);
}
