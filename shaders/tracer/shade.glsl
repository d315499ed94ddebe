// shade.glsl — the Whitted tracer of the report (§2.1): reflection and refraction kept on an
// explicit ray stack (GLSL has no recursion, §3.1), one shadow ray to the point light attenuated by
// the transparencies it crosses, the atmosphere colour for rays that hit nothing, n×n
// supersampling, the BVH overlay lookup (§3.3) and the heatmap mode. Shared code: see geometry.glsl.

struct RayTask {
    vec3 origin;
    vec3 dir;
    vec3 weight;  ///< how much this ray contributes to the pixel
    uint depth;   ///< bounces so far
};

/// Direction of the primary ray through sample (sx, sy) of pixel p: a pinhole camera with vertical
/// field of view 2·atan(camera_position.w), image row 0 at the top.
vec3 camera_ray_dir(uvec2 p, uint sx, uint sy) {
    float n = float(frame.size.z);
    float px = (float(p.x) + (float(sx) + 0.5f) / n) / float(frame.size.x);
    float py = (float(p.y) + (float(sy) + 0.5f) / n) / float(frame.size.y);
    float x = (2.0f * px - 1.0f) * frame.camera_position.w * frame.camera_forward.w;
    float y = (1.0f - 2.0f * py) * frame.camera_position.w;
    return normalize(xyz(frame.camera_forward) + x * xyz(frame.camera_right) + y * xyz(frame.camera_up));
}

/// Geometric normal at a hit, unit length, facing outwards (triangles: by winding).
vec3 surface_normal(Hit hit, vec3 p) {
    if ((hit.ref & REF_SPHERE_BIT) != 0u) {
        vec4 s = load_sphere(hit.ref & REF_INDEX_MASK).center_radius;
        return normalize(p - xyz(s));
    }
    GpuTriangle tri = load_triangle(hit.ref);
    return normalize(cross(xyz(tri.e1), xyz(tri.e2)));
}

/// Ambient, plus diffuse and a Blinn-Phong highlight from the point light, scaled by the shadow
/// ray's transmission. `n` faces the viewer.
vec3 direct_light(vec3 p, vec3 n, vec3 view_dir, vec3 albedo) {
    vec3 to_light = xyz(frame.light_position) - p;
    float dist = length(to_light);
    vec3 l = to_light / dist;
    float lambert = dot(n, l);
    vec3 color = albedo * AMBIENT;
    if (!(lambert > 0.0f)) return color;
    float eps = frame.scale.x;
    float transmission = shadow_transmission(make_ray(p + n * eps, l, 0.0f), dist - eps);
    if (transmission <= 0.0f) return color;
    float highlight = pow(max(dot(n, normalize(l - view_dir)), 0.0f), SHININESS) * SPECULAR;
    return color + xyz(frame.light_color) * (transmission * (1.0f - AMBIENT)) * (albedo * lambert + vec3(highlight));
}

RayTask ray_task(vec3 origin, vec3 dir, vec3 weight, uint depth) {
    RayTask t;
    t.origin = origin;
    t.dir = dir;
    t.weight = weight;
    t.depth = depth;
    return t;
}

/// Colour of one primary ray. `overlay.w` > 0 means the overlay pass drew a BVH line in this
/// pixel at that distance: a primary hit farther away is discarded and the line shows (§3.3).
vec3 trace_sample(vec3 dir, vec4 overlay, INOUT(uint) visited) {
    // Each popped ray pushes at most two, depth first, so at most max_depth + 1 wait at once
    // (MAX_RAY_DEPTH keeps that within RAY_STACK_SIZE).
    RayTask stack[RAY_STACK_SIZE];
    stack[0] = ray_task(xyz(frame.camera_position), dir, vec3(1.0f), 0u);
    uint sp = 1u;
    vec3 color = vec3(0.0f);
    bool primary = true;
    float eps = frame.scale.x;
    while (sp > 0u) {
        sp -= 1u;
        RayTask task = stack[sp];
        bool line = primary && overlay.w > 0.0f;
        Hit hit = closest_hit(make_ray(task.origin, task.dir, 0.0f), line ? overlay.w : FAR_AWAY);
        if (primary) visited = hit.visited;
        primary = false;
        if (hit.ref == NO_HIT) {
            color += task.weight * (line ? xyz(overlay) : xyz(frame.sky));
            continue;
        }
        GpuMaterial m = load_material(material_of(hit.ref));
        float reflective = m.color_reflective.w;
        float transparent = m.transparent_ior.x;
        vec3 p = task.origin + task.dir * hit.t;
        vec3 n = surface_normal(hit, p);
        bool entering = dot(n, task.dir) < 0.0f;
        vec3 facing = entering ? n : -n;
        float opaque = max(1.0f - reflective - transparent, 0.0f);
        if (opaque > 0.0f) color += task.weight * opaque * direct_light(p, facing, task.dir, xyz(m.color_reflective));
        if (task.depth >= frame.size.w) continue;
        // refraction (Snell; total internal reflection turns it into reflection), then reflection
        float reflect_weight = reflective;
        if (transparent > 0.0f) {
            float eta = entering ? 1.0f / m.transparent_ior.y : m.transparent_ior.y;
            vec3 refracted = refract(task.dir, facing, eta);
            if (dot(refracted, refracted) > 0.0f) {
                stack[sp] = ray_task(p - facing * eps, normalize(refracted), task.weight * transparent, task.depth + 1u);
                sp += 1u;
            } else {
                reflect_weight += transparent;
            }
        }
        if (reflect_weight > 0.0f) {
            stack[sp] = ray_task(p + facing * eps, reflect(task.dir, facing), task.weight * reflect_weight, task.depth + 1u);
            sp += 1u;
        }
    }
    return color;
}

/// The pixel: the average of n×n samples; in heatmap mode, the box tests of the primary rays.
vec4 trace_pixel(uvec2 p) {
    vec4 overlay = overlay_at(p);
    uint n = frame.size.z;
    vec3 sum = vec3(0.0f);
    float visits = 0.0f;
    for (uint sy = 0u; sy < n; ++sy) {
        for (uint sx = 0u; sx < n; ++sx) {
            uint visited = 0u;
            sum += trace_sample(camera_ray_dir(p, sx, sy), overlay, visited);
            visits += float(visited);
        }
    }
    float count = float(n * n);
    if (frame.flags.x == MODE_HEATMAP) return vec4(heat_color(visits / count / float(frame.flags.w)), 1.0f);
    return vec4(sum / count, 1.0f);
}
