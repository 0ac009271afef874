// SPDX-License-Identifier: Apache-2.0
// Private: the two triangular passes of implicit Euler's SOR-preconditioned CG (Eisenstat's
// form, see integrator.cpp), in a layout built for SIMD: 3-vectors padded to 4 doubles
// (x, y, z, 0; the fourth stays exactly 0), 3×3 blocks row-major. An AVX2/FMA version is
// chosen at run time when the processor has it, the portable one otherwise; the choice is
// made once per process, so results are deterministic on a given machine (they may differ
// from another machine's in the last bits, FMA rounding).
#pragma once

#include <cstddef>
#include <cstdint>

namespace ido::sim::detail {

/// The upper block triangle of a symmetric block matrix, rows in order, each row's first
/// slot its diagonal block (not read by the kernels).
struct SorMatrix {
  std::size_t rows = 0;
  const std::int32_t* row_offset = nullptr;   ///< rows + 1 entries
  const std::int32_t* col = nullptr;          ///< column of each slot, increasing per row
  const double* blocks = nullptr;   ///< per slot a row-major 3×3 block; 3 readable doubles past the end
  const double* dinv = nullptr;     ///< per row the row-major 3×3 D̃⁻¹; 3 readable doubles past the end
};

/// Backward pass, for i = rows−1 … 0: p_i = σ_i + β p_i; s_i = p_i − Σ_{j>i} U_ij t_j;
/// t_i = D̃_i⁻¹ s_i; g_i = p_i + (ω − 2) s_i (vectors of 4 doubles per row).
void sor_backward(const SorMatrix& a, const double* sigma, double beta, double omega_minus_two,
                  double* p, double* s, double* t, double* g);

/// Forward pass, for i = 0 … rows−1: w_i = D̃_i⁻¹ g_i, then g_j −= U_ijᵀ w_i for the row's
/// j > i (solves (D̃ + L) w = g; g ends as D̃ w).
void sor_forward(const SorMatrix& a, double* g, double* w);

/// q += t over all rows; returns p · q (per-component partial sums, fixed order).
double sor_add_dot(std::size_t rows, double* q, const double* t, const double* p);

/// The CG update: x += α t, ρ −= α q, σ −= α (s + g); returns ρ · σ.
double sor_update(std::size_t rows, double alpha, const double* t, const double* q,
                  const double* s, const double* g, double* x, double* rho, double* sigma);

/// The portable versions of the kernels above (tests compare them with the dispatched ones).
void sor_backward_portable(const SorMatrix& a, const double* sigma, double beta,
                           double omega_minus_two, double* p, double* s, double* t, double* g);
void sor_forward_portable(const SorMatrix& a, double* g, double* w);

/// True when the AVX2/FMA kernels are in use (for the benchmark report).
bool sor_kernels_use_avx2();

}  // namespace ido::sim::detail
