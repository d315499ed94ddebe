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

/// Clip-space position under the tracer's camera (camera_ray in shade.glsl: its screen
/// coordinates, perspective or orthographic; panoramic cameras draw no overlay), Vulkan
/// conventions: y down, depth 0 at the near plane (overlay_near) and 1 at the far plane
/// (overlay_far). A screen point (x, y) lies at image pixel ((x, y) - screen.xy) / screen.zw.
vec4 overlay_clip(vec3 p) {
    vec3 v = p - frame.camera_position;
    float x = dot(v, frame.camera_right);
    float y = dot(v, frame.camera_up);
    float z = dot(v, frame.camera_forward);
    float near = frame.overlay_near;
    float far = frame.overlay_far;
    float sx = 2.0f / (frame.screen.z * float(frame.width));
    float sy = 2.0f / (frame.screen.w * float(frame.height));
    if (frame.projection == PROJECTION_ORTHOGRAPHIC)
        return vec4((x - frame.screen.x) * sx - 1.0f, (y - frame.screen.y) * sy - 1.0f, (z - near) / (far - near), 1.0f);
    return vec4((x - frame.screen.x * z) * sx - z, (y - frame.screen.y * z) * sy - z, far / (far - near) * (z - near), z);
}

/// The distance along the primary ray to a line point at `v` from the camera: from the camera
/// (perspective), along the view axis from the ray's start on the camera's plane (orthographic).
float overlay_distance(vec3 v) {
    return frame.projection == PROJECTION_ORTHOGRAPHIC ? dot(v, frame.camera_forward) : length(v);
}

/// What the overlay's lines are depth-tested by, in [0, 1): where two lines fall on one pixel the
/// nearer shows, and of two in the same step the one drawn first (boxes in depth
/// order). The camera distance `d` as d / (d + far), its float's last 8 bits cleared: steps of
/// 2^-15 of the value (6e-5 of the distance or finer), far above the last-bit differences between
/// the GPU's rasterizer and the CPU reference's. Two box edges on one line (a child's edge on its
/// parent's face) then compare equal in both, and the same box shows; compared unrounded, the
/// two rasterizers' last bits picked different boxes on ~6% of whitted's line pixels.
float overlay_line_depth(float d) {
    d = max(d, 0.0f);  // an orthographic line's end may reach a little behind its start plane
    float q = d / (d + frame.overlay_far);
    return uintBitsToFloat(floatBitsToUint(q) & 0xFFFFFF00u);
}
