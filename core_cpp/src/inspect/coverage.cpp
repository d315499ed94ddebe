// coverage.cpp — what is left of a triangle or a box once the boxes of its parts are taken away
// (coverage.h): convex pieces, each box's six half-spaces cutting a piece into the part outside
// (kept) and the rest (cut again), so every piece stays convex and nothing is left where covered.
#include "coverage.h"

#include <array>
#include <cmath>
#include <cstddef>
#include <vector>

#include "clip_polygon.h"

namespace bvhlab {

namespace {

using Point = std::array<double, 3>;

/// The most pieces followed: a triangle cut into many parts leaves a few pieces at a time (those
/// the boxes not yet taken away cover); past this many, each piece's centre is looked for in the
/// boxes left (covered() below).
constexpr std::size_t kMostPieces = 1 << 14;
/// What is left may be this share of the whole (slivers of rounding where two boxes meet).
constexpr double kLeftShare = 1e-9;

/// The part of a triangle's piece on one side of the plane x[axis] = pos: below it (`below`) or
/// above it (clip_polygon.h); none where fewer than three corners are left.
ClipPolygon cut(const ClipPolygon& piece, int axis, double pos, bool below) {
    ClipPolygon out;
    clip(piece, out, axis, pos, below ? 1.0 : -1.0);
    if (out.n < 3) out.n = 0;
    return out;
}

/// A part's box in double, widened by a margin of rounding: the parts' boxes hold their parts in
/// exact arithmetic (chop.h), and the cuts here round too.
std::array<Point, 2> widened(const Aabb& b, double scale) {
    const double margin = scale * 0x1p-40;
    return {{{b.lo.x - margin, b.lo.y - margin, b.lo.z - margin}, {b.hi.x + margin, b.hi.y + margin, b.hi.z + margin}}};
}

/// Whether the piece (its corners: a polygon's, or a box's low and high) lies outside `box` but
/// for a part of no measure (touching one of its planes at most): kept whole, not cut.
template <class Piece>
bool apart(const Piece& piece, const std::array<Point, 2>& box) {
    for (int k = 0; k < 3; ++k) {
        bool below = true, above = true;
        for (int i = 0; i < piece.n; ++i)
            below = below && piece.p[i][k] <= box[0][k], above = above && piece.p[i][k] >= box[1][k];
        if (below || above) return true;
    }
    return false;
}

/// The mean of the piece's corners: inside it (it is convex).
template <class Piece>
Point centre(const Piece& piece) {
    Point c{0, 0, 0};
    for (int i = 0; i < piece.n; ++i)
        for (int k = 0; k < 3; ++k) c[k] += piece.p[i][k] / double(piece.n);
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
            for (int side = 0; side < 6 && piece.n > 0; ++side) {
                const int axis = side % 3;
                const bool low = side < 3;  // the half-space below the box's low plane is outside it
                const double pos = low ? box[0][axis] : box[1][axis];
                Piece outside = cut_piece(piece, axis, pos, low);
                const double m = outside.n > 0 ? measure(outside) : 0.0;
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

/// A piece of a sphere's box: its low and high corners (n = 2), or none (n = 0).
struct BoxPiece {
    double p[2][3];
    int n = 0;
};

BoxPiece cut_box(const BoxPiece& b, int axis, double pos, bool below) {
    if (!b.n) return b;
    BoxPiece out = b;
    if (below) out.p[1][axis] = std::fmin(out.p[1][axis], pos);
    else out.p[0][axis] = std::fmax(out.p[0][axis], pos);
    if (!(out.p[0][axis] < out.p[1][axis])) out.n = 0;
    return out;
}

double volume(const BoxPiece& b) {
    return b.n ? (b.p[1][0] - b.p[0][0]) * (b.p[1][1] - b.p[0][1]) * (b.p[1][2] - b.p[0][2]) : 0.0;
}

double extent(const Aabb& b) {
    double m = 0;
    for (int k = 0; k < 3; ++k) m = std::fmax(m, std::fmax(std::fabs(double(b.lo[k])), std::fabs(double(b.hi[k]))));
    return std::fmax(m, 1e-30);
}

}  // namespace

bool triangle_covered(const Vec3 v[3], const std::vector<Aabb>& parts) {
    Aabb bounds;
    ClipPolygon triangle;
    triangle.n = 3;
    for (int k = 0; k < 3; ++k) {
        bounds.grow(v[k]);
        for (int a = 0; a < 3; ++a) triangle.p[k][a] = double(v[k][a]);
    }
    return covered(triangle, bounds, parts, extent(bounds), cut, polygon_area);
}

bool box_covered(const Aabb& sphere_box, const std::vector<Aabb>& parts) {
    BoxPiece whole;
    whole.n = 2;
    for (int a = 0; a < 3; ++a) whole.p[0][a] = double(sphere_box.lo[a]), whole.p[1][a] = double(sphere_box.hi[a]);
    return covered(whole, sphere_box, parts, extent(sphere_box), cut_box, volume);
}

}  // namespace bvhlab
