// coverage.cpp — what is left of a triangle or a box once the boxes of its parts are taken away
// (coverage.h): convex pieces, each box's six half-spaces cutting a piece into the part outside
// (kept) and the rest (cut again), so every piece stays convex and nothing is left where covered.
#include "coverage.h"

#include <array>
#include <cmath>
#include <cstddef>

namespace bvhlab {

namespace {

using Point = std::array<double, 3>;
using Polygon = std::vector<Point>;  // convex, in the triangle's plane

/// The most pieces followed: a triangle cut into many parts leaves a few pieces at a time (those
/// the boxes not yet taken away cover); past this many, each piece's centre is looked for in the
/// boxes left (covered() below).
constexpr std::size_t kMostPieces = 1 << 14;
/// What is left may be this share of the whole (slivers of rounding where two boxes meet).
constexpr double kLeftShare = 1e-9;

/// The part of `p` on one side of the plane x[axis] = pos: below it (`below`) or above it
/// (Sutherland and Hodgman 1974, one plane).
Polygon cut(const Polygon& p, int axis, double pos, bool below) {
    Polygon out;
    const auto inside = [&](const Point& q) { return below ? q[axis] <= pos : q[axis] >= pos; };
    for (std::size_t i = 0; i < p.size(); ++i) {
        const Point& a = p[i];
        const Point& b = p[(i + 1) % p.size()];
        if (inside(a)) out.push_back(a);
        if (inside(a) != inside(b) && a[axis] != b[axis]) {
            const double t = (pos - a[axis]) / (b[axis] - a[axis]);
            Point c;
            for (int k = 0; k < 3; ++k) c[k] = k == axis ? pos : a[k] + (b[k] - a[k]) * t;
            out.push_back(c);
        }
    }
    return out.size() >= 3 ? out : Polygon{};
}

double area(const Polygon& p) {
    Point sum{0, 0, 0};  // twice the vector area: the sum of the fan's cross products
    for (std::size_t i = 1; i + 1 < p.size(); ++i) {
        const Point u{p[i][0] - p[0][0], p[i][1] - p[0][1], p[i][2] - p[0][2]};
        const Point w{p[i + 1][0] - p[0][0], p[i + 1][1] - p[0][1], p[i + 1][2] - p[0][2]};
        sum[0] += u[1] * w[2] - u[2] * w[1];
        sum[1] += u[2] * w[0] - u[0] * w[2];
        sum[2] += u[0] * w[1] - u[1] * w[0];
    }
    return 0.5 * std::sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
}

/// A part's box in double, widened by a margin of rounding: the parts' boxes hold their parts in
/// exact arithmetic (chop.h), and the cuts here round too.
std::array<Point, 2> widened(const Aabb& b, double scale) {
    const double margin = scale * 0x1p-40;
    return {{{b.lo.x - margin, b.lo.y - margin, b.lo.z - margin}, {b.hi.x + margin, b.hi.y + margin, b.hi.z + margin}}};
}

/// Whether the piece (its points: a polygon's corners, a box's two) lies outside `box` but for a
/// part of no measure (touching one of its planes at most): kept whole, not cut.
bool apart(const std::vector<Point>& piece, const std::array<Point, 2>& box) {
    for (int k = 0; k < 3; ++k) {
        bool below = true, above = true;
        for (const Point& p : piece) below = below && p[k] <= box[0][k], above = above && p[k] >= box[1][k];
        if (below || above) return true;
    }
    return false;
}

/// The mean of the piece's points: inside it (it is convex).
Point centre(const std::vector<Point>& piece) {
    Point c{0, 0, 0};
    for (const Point& p : piece)
        for (int k = 0; k < 3; ++k) c[k] += p[k] / double(piece.size());
    return c;
}

bool inside(const Point& p, const std::array<Point, 2>& box) {
    return box[0][0] <= p[0] && p[0] <= box[1][0] && box[0][1] <= p[1] && p[1] <= box[1][1] && box[0][2] <= p[2] &&
           p[2] <= box[1][2];
}

template <class Piece, class Cut, class Measure>
bool covered(Piece whole, const Aabb& bounds, const std::vector<Aabb>& parts, double scale, Cut cut_piece,
             Measure measure) {
    for (const Aabb& part : parts) {  // most primitives: one part, a box holding it all
        const auto box = widened(part, scale);
        bool holds = true;
        for (int k = 0; k < 3; ++k) holds = holds && box[0][k] <= bounds.lo[k] && bounds.hi[k] <= box[1][k];
        if (holds) return true;
    }
    const double total = measure(whole);
    if (!(total > 0)) return true;
    // pieces of no measure (a cut along a piece's edge leaves its edge) are dropped, their measure
    // counted as left: kept, they were cut again by every later box and doubled at each (a floor
    // triangle in a column of parts sharing a plane)
    const double negligible = total * 0x1p-60;
    double left = 0;
    std::vector<Piece> pieces{std::move(whole)}, next;
    for (std::size_t i = 0; i < parts.size(); ++i) {
        const auto box = widened(parts[i], scale);
        next.clear();
        for (Piece& piece : pieces) {
            if (apart(piece, box)) {  // most pieces of a primitive in many parts: kept whole
                next.push_back(std::move(piece));
                continue;
            }
            for (int side = 0; side < 6 && !piece.empty(); ++side) {
                const int axis = side % 3;
                const bool low = side < 3;  // the half-space below the box's low plane is outside it
                const double pos = low ? box[0][axis] : box[1][axis];
                Piece outside = cut_piece(piece, axis, pos, low);
                const double m = outside.empty() ? 0.0 : measure(outside);
                if (m > negligible) next.push_back(std::move(outside));
                else left += m;
                piece = cut_piece(piece, axis, pos, !low);
            }
        }
        pieces.swap(next);
        if (pieces.empty()) return left <= kLeftShare * total;
        if (pieces.size() > kMostPieces) {
            // too many to follow: each piece's centre must lie in a box not yet taken away (a
            // point no box holds is uncovered: refused; a covered centre proves less, so accepted)
            for (const Piece& piece : pieces) {
                const Point c = centre(piece);
                bool held = false;
                for (std::size_t j = i + 1; j < parts.size() && !held; ++j) held = inside(c, widened(parts[j], scale));
                if (!held) return false;
            }
            return true;
        }
    }
    for (const Piece& piece : pieces) left += measure(piece);
    return left <= kLeftShare * total;
}

using Box = std::vector<Point>;  // empty, or {lo, hi}

Box cut_box(const Box& b, int axis, double pos, bool below) {
    if (b.empty()) return {};
    Box out = b;
    if (below) out[1][axis] = std::fmin(out[1][axis], pos);
    else out[0][axis] = std::fmax(out[0][axis], pos);
    return out[0][axis] < out[1][axis] ? out : Box{};
}

double volume(const Box& b) { return b.empty() ? 0 : (b[1][0] - b[0][0]) * (b[1][1] - b[0][1]) * (b[1][2] - b[0][2]); }

double extent(const Aabb& b) {
    double m = 0;
    for (int k = 0; k < 3; ++k) m = std::fmax(m, std::fmax(std::fabs(double(b.lo[k])), std::fabs(double(b.hi[k]))));
    return std::fmax(m, 1e-30);
}

}  // namespace

bool triangle_covered(const Vec3 v[3], const std::vector<Aabb>& parts) {
    Aabb bounds;
    Polygon triangle;
    for (int k = 0; k < 3; ++k) {
        bounds.grow(v[k]);
        triangle.push_back({double(v[k].x), double(v[k].y), double(v[k].z)});
    }
    return covered(std::move(triangle), bounds, parts, extent(bounds), cut, area);
}

bool box_covered(const Aabb& sphere_box, const std::vector<Aabb>& parts) {
    Box whole{{double(sphere_box.lo.x), double(sphere_box.lo.y), double(sphere_box.lo.z)},
              {double(sphere_box.hi.x), double(sphere_box.hi.y), double(sphere_box.hi.z)}};
    return covered(std::move(whole), sphere_box, parts, extent(sphere_box), cut_box, volume);
}

}  // namespace bvhlab
