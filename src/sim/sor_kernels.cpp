// SPDX-License-Identifier: Apache-2.0
#include "sor_kernels.h"

#if defined(__GNUC__) && defined(__x86_64__)
#include <immintrin.h>
#define IDO_SIM_HAVE_AVX2_KERNELS 1
#endif

namespace ido::sim::detail {

namespace {

using Index = std::size_t;

inline Index at(std::int32_t k) { return static_cast<Index>(k); }

// out = M v for a row-major 3×3 M; out[3] = 0.
inline void apply3(const double* m, const double* v, double* out) {
  const double v0 = v[0], v1 = v[1], v2 = v[2];
  out[0] = m[0] * v0 + m[1] * v1 + m[2] * v2;
  out[1] = m[3] * v0 + m[4] * v1 + m[5] * v2;
  out[2] = m[6] * v0 + m[7] * v1 + m[8] * v2;
  out[3] = 0.0;
}

}  // namespace

void sor_backward_portable(const SorMatrix& a, const double* sigma, double beta, double om2,
                           double* p, double* s, double* t, double* g) {
  for (Index i = a.rows; i-- > 0;) {
    double* pi = p + 4 * i;
    for (int c = 0; c < 3; ++c) pi[c] = sigma[4 * i + static_cast<Index>(c)] + beta * pi[c];
    double acc0 = pi[0], acc1 = pi[1], acc2 = pi[2];
    for (auto k = a.row_offset[i] + 1; k < a.row_offset[i + 1]; ++k) {
      const double* u = a.blocks + 9 * at(k);
      const double* tj = t + 4 * at(a.col[at(k)]);
      acc0 -= u[0] * tj[0] + u[1] * tj[1] + u[2] * tj[2];
      acc1 -= u[3] * tj[0] + u[4] * tj[1] + u[5] * tj[2];
      acc2 -= u[6] * tj[0] + u[7] * tj[1] + u[8] * tj[2];
    }
    double* si = s + 4 * i;
    si[0] = acc0;
    si[1] = acc1;
    si[2] = acc2;
    si[3] = 0.0;
    apply3(a.dinv + 9 * i, si, t + 4 * i);
    double* gi = g + 4 * i;
    for (int c = 0; c < 3; ++c) gi[c] = pi[c] + om2 * si[c];
    gi[3] = 0.0;
  }
}

void sor_forward_portable(const SorMatrix& a, double* g, double* w) {
  for (Index i = 0; i < a.rows; ++i) {
    double* wi = w + 4 * i;
    apply3(a.dinv + 9 * i, g + 4 * i, wi);
    const double w0 = wi[0], w1 = wi[1], w2 = wi[2];
    for (auto k = a.row_offset[i] + 1; k < a.row_offset[i + 1]; ++k) {
      const double* u = a.blocks + 9 * at(k);
      double* gj = g + 4 * at(a.col[at(k)]);
      gj[0] -= u[0] * w0 + u[3] * w1 + u[6] * w2;
      gj[1] -= u[1] * w0 + u[4] * w1 + u[7] * w2;
      gj[2] -= u[2] * w0 + u[5] * w1 + u[8] * w2;
    }
  }
}

namespace {

double add_dot_portable(Index rows, double* q, const double* t, const double* p) {
  double d0 = 0.0, d1 = 0.0, d2 = 0.0;
  for (Index k = 0; k < 4 * rows; k += 4) {
    q[k] += t[k];
    q[k + 1] += t[k + 1];
    q[k + 2] += t[k + 2];
    d0 += p[k] * q[k];
    d1 += p[k + 1] * q[k + 1];
    d2 += p[k + 2] * q[k + 2];
  }
  return d0 + d1 + d2;
}

double update_portable(Index rows, double alpha, const double* t, const double* q, const double* s,
                       const double* g, double* x, double* rho, double* sigma) {
  double d0 = 0.0, d1 = 0.0, d2 = 0.0;
  for (Index k = 0; k < 4 * rows; k += 4) {
    x[k] += alpha * t[k];
    x[k + 1] += alpha * t[k + 1];
    x[k + 2] += alpha * t[k + 2];
    rho[k] -= alpha * q[k];
    rho[k + 1] -= alpha * q[k + 1];
    rho[k + 2] -= alpha * q[k + 2];
    sigma[k] -= alpha * (s[k] + g[k]);
    sigma[k + 1] -= alpha * (s[k + 1] + g[k + 1]);
    sigma[k + 2] -= alpha * (s[k + 2] + g[k + 2]);
    d0 += rho[k] * sigma[k];
    d1 += rho[k + 1] * sigma[k + 1];
    d2 += rho[k + 2] * sigma[k + 2];
  }
  return d0 + d1 + d2;
}

#ifdef IDO_SIM_HAVE_AVX2_KERNELS

// Lanes (Σ a, Σ b, Σ c, 0) of three 4-lane vectors.
__attribute__((target("avx2,fma"))) inline __m256d hsum3(__m256d a, __m256d b, __m256d c) {
  const __m256d ab = _mm256_hadd_pd(a, b);                       // a01 b01 a23 b23
  const __m256d c0 = _mm256_hadd_pd(c, _mm256_setzero_pd());     // c01 0 c23 0
  return _mm256_add_pd(_mm256_permute2f128_pd(ab, c0, 0x20), _mm256_permute2f128_pd(ab, c0, 0x31));
}

// M v for a row-major 3×3 M (rows loaded 4 wide: the fourth lane meets v's zero).
__attribute__((target("avx2,fma"))) inline __m256d apply3_avx2(const double* m, __m256d v) {
  return hsum3(_mm256_mul_pd(_mm256_loadu_pd(m), v), _mm256_mul_pd(_mm256_loadu_pd(m + 3), v),
               _mm256_mul_pd(_mm256_loadu_pd(m + 6), v));
}

__attribute__((target("avx2,fma"))) void backward_avx2(const SorMatrix& a, const double* sigma,
                                                        double beta, double om2, double* p,
                                                        double* s, double* t, double* g) {
  const __m256d vbeta = _mm256_set1_pd(beta), vom2 = _mm256_set1_pd(om2);
  for (Index i = a.rows; i-- > 0;) {
    const __m256d pi = _mm256_fmadd_pd(vbeta, _mm256_loadu_pd(p + 4 * i), _mm256_loadu_pd(sigma + 4 * i));
    _mm256_storeu_pd(p + 4 * i, pi);
    // Row r of U_ij times t_j, lane by lane (t_j's fourth lane is 0, so the block's
    // neighbouring entry read into a row's fourth lane adds nothing); two blocks at a time.
    // The blocks from the row's end backwards: the first one (column i + 1, whose t was
    // computed just before) comes last, so the row-to-row dependency chain stays short.
    __m256d a0 = _mm256_setzero_pd(), a1 = a0, a2 = a0, b0 = a0, b1 = a0, b2 = a0;
    const auto begin = a.row_offset[i] + 1;
    auto k = a.row_offset[i + 1] - 1;
    for (; k - 1 >= begin; k -= 2) {
      const double* u = a.blocks + 9 * at(k - 1);
      const __m256d tj = _mm256_loadu_pd(t + 4 * at(a.col[at(k) - 1]));
      const __m256d tk = _mm256_loadu_pd(t + 4 * at(a.col[at(k)]));
      b0 = _mm256_fmadd_pd(_mm256_loadu_pd(u + 9), tk, b0);
      b1 = _mm256_fmadd_pd(_mm256_loadu_pd(u + 12), tk, b1);
      b2 = _mm256_fmadd_pd(_mm256_loadu_pd(u + 15), tk, b2);
      a0 = _mm256_fmadd_pd(_mm256_loadu_pd(u), tj, a0);
      a1 = _mm256_fmadd_pd(_mm256_loadu_pd(u + 3), tj, a1);
      a2 = _mm256_fmadd_pd(_mm256_loadu_pd(u + 6), tj, a2);
    }
    if (k >= begin) {
      const double* u = a.blocks + 9 * at(k);
      const __m256d tj = _mm256_loadu_pd(t + 4 * at(a.col[at(k)]));
      a0 = _mm256_fmadd_pd(_mm256_loadu_pd(u), tj, a0);
      a1 = _mm256_fmadd_pd(_mm256_loadu_pd(u + 3), tj, a1);
      a2 = _mm256_fmadd_pd(_mm256_loadu_pd(u + 6), tj, a2);
    }
    const __m256d si = _mm256_sub_pd(
        pi, hsum3(_mm256_add_pd(a0, b0), _mm256_add_pd(a1, b1), _mm256_add_pd(a2, b2)));
    _mm256_storeu_pd(s + 4 * i, si);
    _mm256_storeu_pd(t + 4 * i, apply3_avx2(a.dinv + 9 * i, si));
    _mm256_storeu_pd(g + 4 * i, _mm256_fmadd_pd(vom2, si, pi));
  }
}

__attribute__((target("avx2,fma"))) void forward_avx2(const SorMatrix& a, double* g, double* w) {
  for (Index i = 0; i < a.rows; ++i) {
    const __m256d wi = apply3_avx2(a.dinv + 9 * i, _mm256_loadu_pd(g + 4 * i));
    _mm256_storeu_pd(w + 4 * i, wi);
    const __m256d w0 = _mm256_permute4x64_pd(wi, 0x00), w1 = _mm256_permute4x64_pd(wi, 0x55),
                  w2 = _mm256_permute4x64_pd(wi, 0xAA);
    for (auto k = a.row_offset[i] + 1; k < a.row_offset[i + 1]; ++k) {
      const double* u = a.blocks + 9 * at(k);
      double* gj = g + 4 * at(a.col[at(k)]);
      // U_ijᵀ w_i = Σ_r w_r (row r of U_ij); the fourth lane (another entry) is masked off.
      __m256d d = _mm256_mul_pd(w0, _mm256_loadu_pd(u));
      d = _mm256_fmadd_pd(w1, _mm256_loadu_pd(u + 3), d);
      d = _mm256_fmadd_pd(w2, _mm256_loadu_pd(u + 6), d);
      d = _mm256_blend_pd(d, _mm256_setzero_pd(), 0x8);
      _mm256_storeu_pd(gj, _mm256_sub_pd(_mm256_loadu_pd(gj), d));
    }
  }
}

__attribute__((target("avx2,fma"))) double lane_sum(__m256d v) {
  alignas(32) double l[4];
  _mm256_store_pd(l, v);
  return (l[0] + l[1]) + (l[2] + l[3]);
}

__attribute__((target("avx2,fma"))) double add_dot_avx2(Index rows, double* q, const double* t,
                                                        const double* p) {
  __m256d acc = _mm256_setzero_pd(), acc2 = acc;
  Index i = 0;
  for (; i + 1 < rows; i += 2) {
    const __m256d qi = _mm256_add_pd(_mm256_loadu_pd(q + 4 * i), _mm256_loadu_pd(t + 4 * i));
    const __m256d qk = _mm256_add_pd(_mm256_loadu_pd(q + 4 * i + 4), _mm256_loadu_pd(t + 4 * i + 4));
    _mm256_storeu_pd(q + 4 * i, qi);
    _mm256_storeu_pd(q + 4 * i + 4, qk);
    acc = _mm256_fmadd_pd(_mm256_loadu_pd(p + 4 * i), qi, acc);
    acc2 = _mm256_fmadd_pd(_mm256_loadu_pd(p + 4 * i + 4), qk, acc2);
  }
  if (i < rows) {
    const __m256d qi = _mm256_add_pd(_mm256_loadu_pd(q + 4 * i), _mm256_loadu_pd(t + 4 * i));
    _mm256_storeu_pd(q + 4 * i, qi);
    acc = _mm256_fmadd_pd(_mm256_loadu_pd(p + 4 * i), qi, acc);
  }
  return lane_sum(_mm256_add_pd(acc, acc2));
}

// One row of update_avx2; returns acc + ρ_i σ_i lane by lane.
__attribute__((target("avx2,fma"))) inline __m256d update_row(Index o, __m256d va, const double* t,
                                                              const double* q, const double* s,
                                                              const double* g, double* x, double* rho,
                                                              double* sigma, __m256d acc) {
  _mm256_storeu_pd(x + o, _mm256_fmadd_pd(va, _mm256_loadu_pd(t + o), _mm256_loadu_pd(x + o)));
  const __m256d r = _mm256_fnmadd_pd(va, _mm256_loadu_pd(q + o), _mm256_loadu_pd(rho + o));
  const __m256d sg = _mm256_add_pd(_mm256_loadu_pd(s + o), _mm256_loadu_pd(g + o));
  const __m256d sv = _mm256_fnmadd_pd(va, sg, _mm256_loadu_pd(sigma + o));
  _mm256_storeu_pd(rho + o, r);
  _mm256_storeu_pd(sigma + o, sv);
  return _mm256_fmadd_pd(r, sv, acc);
}

__attribute__((target("avx2,fma"))) double update_avx2(Index rows, double alpha, const double* t,
                                                       const double* q, const double* s,
                                                       const double* g, double* x, double* rho,
                                                       double* sigma) {
  const __m256d va = _mm256_set1_pd(alpha);
  __m256d acc = _mm256_setzero_pd(), acc2 = acc;
  Index i = 0;
  for (; i + 1 < rows; i += 2) {
    acc = update_row(4 * i, va, t, q, s, g, x, rho, sigma, acc);
    acc2 = update_row(4 * i + 4, va, t, q, s, g, x, rho, sigma, acc2);
  }
  if (i < rows) acc = update_row(4 * i, va, t, q, s, g, x, rho, sigma, acc);
  return lane_sum(_mm256_add_pd(acc, acc2));
}

bool detect_avx2() {
  __builtin_cpu_init();
  return __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
}

#endif

}  // namespace

bool sor_kernels_use_avx2() {
#ifdef IDO_SIM_HAVE_AVX2_KERNELS
  static const bool avx2 = detect_avx2();
  return avx2;
#else
  return false;
#endif
}

void sor_backward(const SorMatrix& a, const double* sigma, double beta, double omega_minus_two,
                  double* p, double* s, double* t, double* g) {
#ifdef IDO_SIM_HAVE_AVX2_KERNELS
  if (sor_kernels_use_avx2()) return backward_avx2(a, sigma, beta, omega_minus_two, p, s, t, g);
#endif
  sor_backward_portable(a, sigma, beta, omega_minus_two, p, s, t, g);
}

void sor_forward(const SorMatrix& a, double* g, double* w) {
#ifdef IDO_SIM_HAVE_AVX2_KERNELS
  if (sor_kernels_use_avx2()) return forward_avx2(a, g, w);
#endif
  sor_forward_portable(a, g, w);
}

double sor_add_dot(std::size_t rows, double* q, const double* t, const double* p) {
#ifdef IDO_SIM_HAVE_AVX2_KERNELS
  if (sor_kernels_use_avx2()) return add_dot_avx2(rows, q, t, p);
#endif
  return add_dot_portable(rows, q, t, p);
}

double sor_update(std::size_t rows, double alpha, const double* t, const double* q,
                  const double* s, const double* g, double* x, double* rho, double* sigma) {
#ifdef IDO_SIM_HAVE_AVX2_KERNELS
  if (sor_kernels_use_avx2()) return update_avx2(rows, alpha, t, q, s, g, x, rho, sigma);
#endif
  return update_portable(rows, alpha, t, q, s, g, x, rho, sigma);
}

}  // namespace ido::sim::detail
