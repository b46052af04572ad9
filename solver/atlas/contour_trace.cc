// Tracing a structure's pixels on a plate into polygons along the pixel
// faces, and drawing polygons back onto the pixel grid (contours.h). The
// JSON form of contours is in contours.cc.
//
// The two are exact inverses on one grid: traced vertices lie on pixel faces,
// half a pixel from every pixel centre and every row's scanline, so the
// rasteriser never meets a polygon edge or vertex at a centre and no
// tolerance is needed.

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <vector>

#include "atlas/contours.h"

namespace pba {
namespace {

// Directions of the pixel-face edges, counter-clockwise in x-right/y-up
// coordinates so that (d + 1) % 4 is a left turn from d.
enum Direction { kRight = 0, kUp = 1, kLeft = 2, kDown = 3 };

// A directed pixel-face edge between face-grid vertices: vertex (i, j) is
// the corner shared by pixels (i - 1, j - 1) .. (i, j), i.e. the top-left
// corner of pixel (i, j).
struct Edge {
  int from = 0;  // vertex index in the local vertex grid
  int to = 0;
  Direction direction = kRight;
};

// Pixels of `label` on one plate, bounded by [c0, c1) x [r0, r1); empty
// when c0 == c1.
struct Box {
  int c0 = 0, c1 = 0, r0 = 0, r1 = 0;
};

Box LabelBox(const PlateStack& stack, int plate, uint16_t label) {
  Box box{stack.width, 0, stack.height, 0};
  const std::vector<uint16_t>& labels = stack.labels[plate];
  for (int r = 0; r < stack.height; ++r) {
    const uint16_t* row = labels.data() + static_cast<size_t>(r) * stack.width;
    for (int c = 0; c < stack.width; ++c) {
      if (row[c] != label) continue;
      box.c0 = std::min(box.c0, c);
      box.c1 = std::max(box.c1, c + 1);
      box.r0 = std::min(box.r0, r);
      box.r1 = std::max(box.r1, r + 1);
    }
  }
  if (box.c1 == 0) return Box{};
  return box;
}

}  // namespace

void RasterizeContourPlate(const ContourPlate& plate, const Eigen::Vector2d& origin_mm,
                           double pixel_mm, int width, int height, uint16_t label,
                           std::vector<uint16_t>* labels) {
  // A grid that does not match its label image is a caller's bug; drawing
  // nothing is safer than writing past the image.
  if (!(pixel_mm > 0) || width <= 0 || height <= 0 ||
      labels->size() != static_cast<size_t>(width) * height) {
    return;
  }
  // An active-edge table: each edge is bucketed at the first row it may
  // cross and dropped after the last, so a row looks only at the edges
  // spanning it. The bounds are widened by a row each way; the exact test
  // below decides.
  struct Span {
    Eigen::Vector2d a, b;
    int last_row;
  };
  std::vector<std::vector<Span>> starting(height);
  for (const std::vector<Eigen::Vector2d>& polygon : plate.polygons) {
    const size_t n = polygon.size();
    for (size_t i = 0; i < n; ++i) {
      const Eigen::Vector2d& a = polygon[i];
      const Eigen::Vector2d& b = polygon[(i + 1) % n];
      if (a.y() == b.y() || !a.allFinite() || !b.allFinite()) continue;
      const double first = std::floor((origin_mm.y() - std::max(a.y(), b.y())) / pixel_mm) - 1;
      const double last = std::ceil((origin_mm.y() - std::min(a.y(), b.y())) / pixel_mm) + 1;
      if (last < 0 || first >= height) continue;
      const int r0 = static_cast<int>(std::max(first, 0.0));
      starting[r0].push_back({a, b, static_cast<int>(std::min<double>(last, height - 1))});
    }
  }
  std::vector<Span> active;
  std::vector<double> crossings;
  for (int r = 0; r < height; ++r) {
    const double y = origin_mm.y() - r * pixel_mm;
    active.erase(std::remove_if(active.begin(), active.end(),
                                [r](const Span& span) { return span.last_row < r; }),
                 active.end());
    active.insert(active.end(), starting[r].begin(), starting[r].end());
    crossings.clear();
    for (const Span& span : active) {
      const Eigen::Vector2d& a = span.a;
      const Eigen::Vector2d& b = span.b;
      // Half-open in y: an edge owns its lower end, not its upper one, so
      // a vertex on the scanline is crossed once when the polygon passes
      // through it and zero or two times when it only touches it.
      if ((a.y() <= y) == (b.y() <= y)) continue;
      crossings.push_back(a.x() + (y - a.y()) * (b.x() - a.x()) / (b.y() - a.y()));
    }
    std::sort(crossings.begin(), crossings.end());
    uint16_t* row = labels->data() + static_cast<size_t>(r) * width;
    for (size_t i = 0; i + 1 < crossings.size(); i += 2) {
      // Centres x with crossings[i] <= x < crossings[i + 1]: half-open in x
      // as well, so two polygons sharing an edge do not both claim a centre
      // on it.
      const double first = std::ceil((crossings[i] - origin_mm.x()) / pixel_mm);
      const double end = std::ceil((crossings[i + 1] - origin_mm.x()) / pixel_mm);
      const int c0 = static_cast<int>(std::clamp(first, 0.0, static_cast<double>(width)));
      const int c1 = static_cast<int>(std::clamp(end, 0.0, static_cast<double>(width)));
      for (int c = c0; c < c1; ++c) row[c] = label;
    }
  }
}

ContourPlate TraceContourPlate(const PlateStack& stack, int plate, uint16_t label) {
  ContourPlate result;
  result.z_mm = stack.z_mm[plate];
  const Box box = LabelBox(stack, plate, label);
  if (box.c0 == box.c1) return result;

  // Vertices of the faces around the box: (box.c0 .. box.c1) x (box.r0 ..
  // box.r1), numbered locally so the work is proportional to the
  // structure's extent, not to the plate's.
  const int vertex_columns = box.c1 - box.c0 + 1;
  const int vertex_rows = box.r1 - box.r0 + 1;
  const auto vertex = [&](int i, int j) { return (j - box.r0) * vertex_columns + (i - box.c0); };
  const auto is_label = [&](int c, int r) {
    return c >= 0 && r >= 0 && c < stack.width && r < stack.height &&
           stack.at(plate, c, r) == label;
  };

  // Every face between a label pixel and another pixel (or the grid's
  // border), directed so the label pixel is on its left: outer boundaries
  // come out counter-clockwise and holes clockwise.
  std::vector<Edge> edges;
  for (int r = box.r0; r < box.r1; ++r) {
    for (int c = box.c0; c < box.c1; ++c) {
      if (!is_label(c, r)) continue;
      // Row r - 1 is above (larger y): the top face runs right to left.
      if (!is_label(c, r - 1)) edges.push_back({vertex(c + 1, r), vertex(c, r), kLeft});
      if (!is_label(c, r + 1)) edges.push_back({vertex(c, r + 1), vertex(c + 1, r + 1), kRight});
      if (!is_label(c - 1, r)) edges.push_back({vertex(c, r), vertex(c, r + 1), kDown});
      if (!is_label(c + 1, r)) edges.push_back({vertex(c + 1, r + 1), vertex(c + 1, r), kUp});
    }
  }

  // At most two edges leave a vertex: two where label pixels touch only
  // diagonally there.
  std::vector<std::array<int, 2>> leaving(static_cast<size_t>(vertex_columns) * vertex_rows,
                                          {-1, -1});
  for (int e = 0; e < static_cast<int>(edges.size()); ++e) {
    std::array<int, 2>& out = leaving[edges[e].from];
    out[out[0] < 0 ? 0 : 1] = e;
  }
  // The edge after `e`: the only one leaving its end, or where two leave
  // (a diagonal touch), the left turn. That turn keeps to the label pixel
  // `e` bounds, so pixels touching at a corner get separate loops (label
  // pixels are joined by faces, background by faces or corners) and loops
  // touch at such a vertex without crossing. The choice depends only on
  // `e`, so each edge has exactly one successor and one predecessor.
  const auto next = [&](int e) {
    const std::array<int, 2>& out = leaving[edges[e].to];
    if (out[1] < 0) return out[0];
    const Direction left = static_cast<Direction>((edges[e].direction + 1) % 4);
    return edges[out[0]].direction == left ? out[0] : out[1];
  };

  const double h = stack.pixel_size_mm;
  const auto point = [&](int v) {
    const int i = box.c0 + v % vertex_columns;
    const int j = box.r0 + v / vertex_columns;
    return Eigen::Vector2d(stack.origin_mm.x() + (i - 0.5) * h,
                           stack.origin_mm.y() - (j - 0.5) * h);
  };
  std::vector<char> used(edges.size(), 0);
  std::vector<int> loop;
  for (int start = 0; start < static_cast<int>(edges.size()); ++start) {
    if (used[start]) continue;
    loop.clear();
    for (int e = start; !used[e]; e = next(e)) {
      used[e] = 1;
      loop.push_back(e);
    }
    // A corner wherever the direction changes; the points in between are
    // collinear with their neighbours.
    std::vector<Eigen::Vector2d> polygon;
    const size_t n = loop.size();
    for (size_t k = 0; k < n; ++k) {
      const Edge& before = edges[loop[(k + n - 1) % n]];
      const Edge& edge = edges[loop[k]];
      if (before.direction != edge.direction) polygon.push_back(point(edge.from));
    }
    result.polygons.push_back(std::move(polygon));
  }
  return result;
}

Contours TraceContours(const PlateStack& stack, uint16_t label) {
  Contours contours;
  contours.pixel_size_mm = stack.pixel_size_mm;
  for (int p = 0; p < stack.num_plates(); ++p) {
    ContourPlate plate = TraceContourPlate(stack, p, label);
    if (!plate.polygons.empty()) contours.plates.push_back(std::move(plate));
  }
  return contours;
}

}  // namespace pba
