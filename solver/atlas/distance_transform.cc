#include "atlas/distance_transform.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace pba {
namespace {

constexpr double kFar = std::numeric_limits<double>::infinity();

// Squared 1-D distance transform of the sampled function f (n samples):
// d[q] = min_p ((q - p)^2 + f[p]), as the lower envelope of the parabolas
// rooted at the finite samples (Felzenszwalb & Huttenlocher 2012,
// algorithm DT(f)). Infinite samples root no parabola; with none finite
// every d is infinite. v (n ints) and z (n + 1 doubles) are scratch.
void SquaredDistance1d(const double* f, int n, double* d, int* v, double* z) {
  int k = -1;
  for (int q = 0; q < n; ++q) {
    if (!std::isfinite(f[q])) continue;
    double s = -kFar;
    while (k >= 0) {
      const int p = v[k];
      s = ((f[q] + double(q) * q) - (f[p] + double(p) * p)) / (2.0 * (q - p));
      if (s > z[k]) break;
      --k;
    }
    ++k;
    v[k] = q;
    z[k] = k == 0 ? -kFar : s;
    z[k + 1] = kFar;
  }
  if (k < 0) {
    std::fill(d, d + n, kFar);
    return;
  }
  int j = 0;
  for (int q = 0; q < n; ++q) {
    while (z[j + 1] < q) ++j;
    const double dq = q - v[j];
    d[q] = dq * dq + f[v[j]];
  }
}

}  // namespace

void SquaredDistanceTransform2d(const std::vector<uint8_t>& feature, int w, int h,
                                std::vector<double>* out) {
  const int n = std::max(w, h);
  std::vector<double> f(n), d(n), z(n + 1);
  std::vector<int> v(n);
  out->assign(static_cast<size_t>(w) * h, kFar);
  for (int c = 0; c < w; ++c) {
    for (int r = 0; r < h; ++r) f[r] = feature[static_cast<size_t>(r) * w + c] ? 0.0 : kFar;
    SquaredDistance1d(f.data(), h, d.data(), v.data(), z.data());
    for (int r = 0; r < h; ++r) (*out)[static_cast<size_t>(r) * w + c] = d[r];
  }
  for (int r = 0; r < h; ++r) {
    double* row = out->data() + static_cast<size_t>(r) * w;
    std::copy(row, row + w, f.begin());
    SquaredDistance1d(f.data(), w, row, v.data(), z.data());
  }
}

void SquaredDistanceTransform3d(const std::vector<uint8_t>& feature, int nx, int ny, int nz,
                                std::vector<double>* out) {
  const size_t slice = static_cast<size_t>(nx) * ny;
  out->assign(slice * nz, kFar);
  std::vector<uint8_t> plane(slice);
  std::vector<double> d2;
  for (int k = 0; k < nz; ++k) {
    std::copy(feature.begin() + k * slice, feature.begin() + (k + 1) * slice, plane.begin());
    SquaredDistanceTransform2d(plane, nx, ny, &d2);
    std::copy(d2.begin(), d2.end(), out->begin() + k * slice);
  }
  // Then along z, on the in-plane squared distances (the transform is
  // separable: the lower envelope works on any sampled function).
  std::vector<double> f(nz), d(nz), z(nz + 1);
  std::vector<int> v(nz);
  for (size_t i = 0; i < slice; ++i) {
    for (int k = 0; k < nz; ++k) f[k] = (*out)[i + k * slice];
    SquaredDistance1d(f.data(), nz, d.data(), v.data(), z.data());
    for (int k = 0; k < nz; ++k) (*out)[i + k * slice] = d[k];
  }
}

void SquaredDistanceTransform3dMm(const std::vector<uint8_t>& feature, int nx, int ny, int nz,
                                  const double spacing_mm[3], std::vector<double>* out) {
  const int n[3] = {nx, ny, nz};
  const size_t stride[3] = {1, static_cast<size_t>(nx), static_cast<size_t>(nx) * ny};
  const size_t total = stride[2] * nz;
  out->resize(total);
  for (size_t i = 0; i < total; ++i) (*out)[i] = feature[i] ? 0.0 : kFar;
  const int longest = std::max({nx, ny, nz});
  std::vector<double> f(longest), d(longest), z(longest + 1);
  std::vector<int> v(longest);
  // One axis at a time: along axis a, min_p (h^2 (q - p)^2 + g[p]) is h^2
  // times the unit-spacing transform of g / h^2.
  for (int a = 0; a < 3; ++a) {
    const double h2 = spacing_mm[a] * spacing_mm[a];
    const int b = a == 0 ? 1 : 0, c = a == 2 ? 1 : 2;
    for (int jb = 0; jb < n[b]; ++jb) {
      for (int jc = 0; jc < n[c]; ++jc) {
        const size_t base = jb * stride[b] + jc * stride[c];
        for (int q = 0; q < n[a]; ++q) f[q] = (*out)[base + q * stride[a]] / h2;
        SquaredDistance1d(f.data(), n[a], d.data(), v.data(), z.data());
        for (int q = 0; q < n[a]; ++q) (*out)[base + q * stride[a]] = d[q] * h2;
      }
    }
  }
}

}  // namespace pba
