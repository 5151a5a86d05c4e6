// LineExtractor: carpet-relative white-line crossings along precomputed pixel rays (vision.hpp).
#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <opencv2/imgproc.hpp>

#include "hsv_tables.hpp"
#include "omniloc/camera.hpp"
#include "omniloc/conventions.hpp"
#include "omniloc/detail/line_extractor.hpp"
#include "omniloc/line_scan.hpp"
#include "omniloc/vision.hpp"

#if defined(__x86_64__) || defined(__i386__)
#include <immintrin.h>
#define OMNILOC_HAVE_X86 1
#endif

namespace omniloc {

namespace {

constexpr int kMaxRaysPerDegree = 20;

// OpenCV 8-bit hue (0..179) of BGR p with max v and max - min diff.
inline int hue_of(const std::uint8_t* p, int v, int diff, const int* hdiv) {
  const int b = p[0], g = p[1], r = p[2];
  int h;
  if (v == r)
    h = g - b;
  else if (v == g)
    h = b - r + 2 * diff;
  else
    h = r - g + 4 * diff;
  h = (h * hdiv[diff] + (1 << 11)) >> 12;
  return h < 0 ? h + 180 : (h >= 180 ? h - 180 : h);
}

#ifdef OMNILOC_HAVE_X86
bool cpu_has_avx2() {
  static const bool has =
      __builtin_cpu_supports("avx2") != 0;  // CPU feature, fixed for the process
  return has;
}

// The divisors of OpenCV's integer HSV (hsv_tables.hpp) for 8 lanes, from a float division rounded
// to nearest: sat_div[v] = round(255 * 4096 / v), hue_div[d] = round(30 * 4096 / d) (a lane of 0
// gets the divisor of 1; it is multiplied by a difference of 0). hsv_divisors_match() checks them
// against the tables for every value once, before they are used.
__attribute__((target("avx2"))) inline __m256i sat_div8(__m256i v) {
  const __m256 q = _mm256_div_ps(_mm256_set1_ps(255.0f * 4096.0f),
                                 _mm256_cvtepi32_ps(_mm256_max_epi32(v, _mm256_set1_epi32(1))));
  return _mm256_cvttps_epi32(_mm256_round_ps(q, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC));
}
__attribute__((target("avx2"))) inline __m256i hue_div8(__m256i d) {
  const __m256 q = _mm256_div_ps(_mm256_set1_ps(30.0f * 4096.0f),
                                 _mm256_cvtepi32_ps(_mm256_max_epi32(d, _mm256_set1_epi32(1))));
  return _mm256_cvttps_epi32(_mm256_round_ps(q, _MM_FROUND_TO_NEAREST_INT | _MM_FROUND_NO_EXC));
}
__attribute__((target("avx2"))) bool hsv_divisors_match_avx2() {
  const int* sdiv = detail::hsv_tables().sat_div;
  const int* hdiv = detail::hsv_tables().hue_div;
  for (int i = 1; i < 256; i += 8) {
    alignas(32) std::int32_t s[8], h[8];
    const __m256i x =
        _mm256_add_epi32(_mm256_set1_epi32(i), _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7));
    _mm256_store_si256(reinterpret_cast<__m256i*>(s), sat_div8(x));
    _mm256_store_si256(reinterpret_cast<__m256i*>(h), hue_div8(x));
    for (int k = 0; k < 8 && i + k < 256; ++k)
      if (s[k] != sdiv[i + k] || h[k] != hdiv[i + k]) return false;
  }
  return true;
}
bool hsv_divisors_match() {
  static const bool match =
      hsv_divisors_match_avx2();  // a property of the CPU's float division, fixed
  return match;
}

// The carpet's hue window as at most two ranges of the 8-bit hue (it may wrap round 0).
struct HueRanges {
  int lo[2] = {1, 1}, hi[2] = {0, 0};  // empty
};
bool hue_ranges(const std::array<bool, 180>& ok, HueRanges& out) {
  int n = 0;
  for (int i = 0; i < 180; ++i) {
    if (!ok[static_cast<std::size_t>(i)] || (i > 0 && ok[static_cast<std::size_t>(i - 1)]))
      continue;
    if (n == 2) return false;
    int j = i;
    while (j + 1 < 180 && ok[static_cast<std::size_t>(j + 1)]) ++j;
    out.lo[n] = i;
    out.hi[n] = j;
    ++n;
  }
  return true;
}

// code_pixels' word for 8 pixels at p (24 bytes; 28 are read): V | S << 8 | carpet hue << 16, with
// OpenCV's integer HSV exactly as the scalar loop.
__attribute__((target("avx2"))) inline __m256i code8_avx2(const std::uint8_t* p,
                                                          const HueRanges& hr_ok,
                                                          __m256i sat_min_minus_1) {
  const __m256i x = _mm256_inserti128_si256(
      _mm256_castsi128_si256(_mm_loadu_si128(reinterpret_cast<const __m128i*>(p))),
      _mm_loadu_si128(reinterpret_cast<const __m128i*>(p + 12)), 1);
  // Each 128-bit half holds 4 pixels (12 bytes): their b, g and r bytes to 32-bit lanes.
  const __m256i mb = _mm256_setr_epi8(0, -1, -1, -1, 3, -1, -1, -1, 6, -1, -1, -1, 9, -1, -1, -1, 0,
                                      -1, -1, -1, 3, -1, -1, -1, 6, -1, -1, -1, 9, -1, -1, -1);
  const __m256i mg = _mm256_setr_epi8(1, -1, -1, -1, 4, -1, -1, -1, 7, -1, -1, -1, 10, -1, -1, -1,
                                      1, -1, -1, -1, 4, -1, -1, -1, 7, -1, -1, -1, 10, -1, -1, -1);
  const __m256i mr = _mm256_setr_epi8(2, -1, -1, -1, 5, -1, -1, -1, 8, -1, -1, -1, 11, -1, -1, -1,
                                      2, -1, -1, -1, 5, -1, -1, -1, 8, -1, -1, -1, 11, -1, -1, -1);
  const __m256i b = _mm256_shuffle_epi8(x, mb), g = _mm256_shuffle_epi8(x, mg),
                r = _mm256_shuffle_epi8(x, mr);
  const __m256i v = _mm256_max_epi32(_mm256_max_epi32(b, g), r);
  const __m256i diff = _mm256_sub_epi32(v, _mm256_min_epi32(_mm256_min_epi32(b, g), r));
  const __m256i round = _mm256_set1_epi32(1 << 11);
  const __m256i s =
      _mm256_srli_epi32(_mm256_add_epi32(_mm256_mullo_epi32(diff, sat_div8(v)), round), 12);
  const __m256i hr = _mm256_sub_epi32(g, b);
  const __m256i hg = _mm256_add_epi32(_mm256_sub_epi32(b, r), _mm256_slli_epi32(diff, 1));
  const __m256i hb = _mm256_add_epi32(_mm256_sub_epi32(r, g), _mm256_slli_epi32(diff, 2));
  const __m256i h0 = _mm256_blendv_epi8(_mm256_blendv_epi8(hb, hg, _mm256_cmpeq_epi32(v, g)), hr,
                                        _mm256_cmpeq_epi32(v, r));
  __m256i h =
      _mm256_srai_epi32(_mm256_add_epi32(_mm256_mullo_epi32(h0, hue_div8(diff)), round), 12);
  const __m256i k180 = _mm256_set1_epi32(180);
  h = _mm256_add_epi32(h, _mm256_and_si256(k180, _mm256_cmpgt_epi32(_mm256_setzero_si256(), h)));
  h = _mm256_sub_epi32(h, _mm256_and_si256(k180, _mm256_cmpgt_epi32(h, _mm256_set1_epi32(179))));
  const __m256i in0 = _mm256_and_si256(_mm256_cmpgt_epi32(h, _mm256_set1_epi32(hr_ok.lo[0] - 1)),
                                       _mm256_cmpgt_epi32(_mm256_set1_epi32(hr_ok.hi[0] + 1), h));
  const __m256i in1 = _mm256_and_si256(_mm256_cmpgt_epi32(h, _mm256_set1_epi32(hr_ok.lo[1] - 1)),
                                       _mm256_cmpgt_epi32(_mm256_set1_epi32(hr_ok.hi[1] + 1), h));
  const __m256i flag =
      _mm256_and_si256(_mm256_or_si256(in0, in1), _mm256_cmpgt_epi32(s, sat_min_minus_1));
  return _mm256_or_si256(_mm256_or_si256(v, _mm256_slli_epi32(s, 8)),
                         _mm256_srli_epi32(_mm256_slli_epi32(flag, 31), 15));
}

// The rows of code_pixels_avx2: [row_u0, row_u1] of each row, 8 pixels at a time, the rest scalar.
__attribute__((target("avx2"))) void code_rows_avx2(const cv::Mat& bgr, const std::int32_t* row_u0,
                                                    const std::int32_t* row_u1, std::uint32_t* code,
                                                    const HueRanges& hue_ok, int sat_min) {
  const int* sdiv = detail::hsv_tables().sat_div;
  const int* hdiv = detail::hsv_tables().hue_div;
  const __m256i sat_min_minus_1 = _mm256_set1_epi32(sat_min - 1);
  // 28 bytes are read for 8 pixels: stay inside the image's last row.
  const std::uint8_t* data_end = bgr.ptr<std::uint8_t>(bgr.rows - 1) + 3 * bgr.cols;
  for (int row = 0; row < bgr.rows; ++row) {
    const int u0 = row_u0[row], u1 = row_u1[row];
    const std::uint8_t* p = bgr.ptr<std::uint8_t>(row) + 3 * u0;
    std::uint32_t* out = code + static_cast<std::size_t>(row) * static_cast<std::size_t>(bgr.cols);
    int u = u0;
    for (; u + 7 <= u1 && p + 28 <= data_end; u += 8, p += 24) {
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(out + u),
                          code8_avx2(p, hue_ok, sat_min_minus_1));
    }
    for (; u <= u1; ++u, p += 3) {
      const int v = std::max({p[0], p[1], p[2]});
      const int diff = v - std::min({p[0], p[1], p[2]});
      const int s = (diff * sdiv[v] + (1 << 11)) >> 12;
      const int h = hue_of(p, v, diff, hdiv);
      const bool carpet_hue = s >= sat_min && ((h >= hue_ok.lo[0] && h <= hue_ok.hi[0]) ||
                                               (h >= hue_ok.lo[1] && h <= hue_ok.hi[1]));
      out[u] = static_cast<std::uint32_t>(v) | static_cast<std::uint32_t>(s) << 8 |
               static_cast<std::uint32_t>(carpet_hue) << 16;
    }
  }
}

// The lockstep walk: 8 rays (lanes) walked bin by bin together, each lane making walk_fast's
// decisions for its own ray without branches (line, carpet or other; the running carpet means; the
// end run). What the rare decisions need (the white runs, the deviation histograms) is written per
// step and lane (index 8 s + l) and taken up by scalar code afterwards:
//   rec:  the bin's brightest pixel (walk_fast's prev_v) | its line V (0: not a line bin) << 8 |
//         the running carpet mean (Q8, as the bin saw it) << 16
//   hist: a carpet bin's rounded deviations dv, ds from the running means: (dv + 32) * 64 + ds + 32
//         when both lie in [-32, 31], kHistWide | (dv + 255) | (ds + 255) << 12 otherwise;
//         kHistNone + l for any other bin
//   line: bit s % 32 of word 8 (s / 32) + l set for a line bin
constexpr int kHistNone = 4096;
constexpr std::uint32_t kHistWide = 0x80000000u;

struct LockConsts {
  int val_step_q = 0, sat_step_q = 0, end_run_px = 0, alpha_q = 0, alpha_shift = -1;
  int carpet_resume_px = 1, resume_within_px = 1;
  bool histogram = true;  // the deviation histograms are wanted (the line steps are estimated)
};
struct LockLanes {
  // In: the lane's bins, starting carpet means (Q8) and carpet value window.
  alignas(32) std::int32_t bins[8], vref[8], sref[8], vmin[8], vmax[8];
  // Out: bins walked (up to and including the one that ended the ray), the step that ended it
  // (-1: none), its carpet bins and their sums of V and S, and whether the carpet resumed behind
  // the end (walk_fast's look behind: carpet_resume_px carpet bins in a row within
  // resume_within_px).
  alignas(32) std::int32_t walked[8], end_step[8], carpet[8], sum_v[8], sum_s[8], resumed[8];
};

__attribute__((target("avx2"))) inline __m256i load8(const std::int32_t* p) {
  return _mm256_load_si256(reinterpret_cast<const __m256i*>(p));
}
__attribute__((target("avx2"))) inline void store8(std::int32_t* p, __m256i x) {
  _mm256_store_si256(reinterpret_cast<__m256i*>(p), x);
}

// Eight words by eight scalar loads: faster here than the gather instruction (which costs about
// as much as 16 loads on the machines measured, docs/VISION.md).
__attribute__((target("avx2"))) inline __m256i gather8(const int* base, const std::int32_t* at) {
  return _mm256_setr_epi32(base[at[0]], base[at[1]], base[at[2]], base[at[3]], base[at[4]],
                           base[at[5]], base[at[6]], base[at[7]]);
}

// The stages below are inlined into walk_group_avx2 (always_inline): its state stays in registers.

// walk_group_avx2's constants: per lane (bins, value window) and broadcast.
struct GroupConsts {
  __m256i bins, one, m255, vmin_m1, vmax_p1, vstep, sstep, flag_min, end_run_m1, c32, c128, not63;
  __m256i none_lane, wide_bit, alpha, resume_m1, look_reach, bins_m2;
  __m128i shift;
};

__attribute__((target("avx2"), always_inline)) inline GroupConsts group_consts(
    const LockConsts& k, const LockLanes& ln) {
  GroupConsts c;
  c.bins = load8(ln.bins);
  c.one = _mm256_set1_epi32(1);
  c.m255 = _mm256_set1_epi32(255);
  c.vmin_m1 = _mm256_sub_epi32(load8(ln.vmin), c.one);
  c.vmax_p1 = _mm256_add_epi32(load8(ln.vmax), c.one);
  c.vstep = _mm256_set1_epi32(k.val_step_q + 255);
  c.sstep = _mm256_set1_epi32(k.sat_step_q);
  c.flag_min = _mm256_set1_epi32(0xffff);
  c.end_run_m1 = _mm256_set1_epi32(k.end_run_px - 1);
  c.c32 = _mm256_set1_epi32(32);
  c.c128 = _mm256_set1_epi32(128);
  c.not63 = _mm256_set1_epi32(~63);
  // One "none" slot per lane: back-to-back increments of one counter would wait on each other.
  c.none_lane = _mm256_setr_epi32(kHistNone, kHistNone + 1, kHistNone + 2, kHistNone + 3,
                                  kHistNone + 4, kHistNone + 5, kHistNone + 6, kHistNone + 7);
  c.wide_bit = _mm256_set1_epi32(static_cast<int>(kHistWide | 255u | (255u << 12)));
  c.shift = _mm_cvtsi32_si128(k.alpha_shift >= 0 ? k.alpha_shift : 0);
  c.alpha = _mm256_set1_epi32(k.alpha_q);
  c.resume_m1 = _mm256_set1_epi32(k.carpet_resume_px - 1);
  c.look_reach = _mm256_set1_epi32(k.resume_within_px - k.end_run_px);
  c.bins_m2 = _mm256_sub_epi32(c.bins, _mm256_set1_epi32(2));
  return c;
}

// The lanes' state through the walk: running means (Q8) and the line test's bounds (v >= v_line_min
// <=> v > vl, s <= s_line_max <=> sl > s), alive (not ended), the end run, the counts and sums,
// the line bits of the current 32 steps, and the look behind an end (lanes looking for the carpet
// up to their last step to look at, the run of carpet bins, whether it was found).
struct GroupState {
  __m256i vref, sref, vl, sl, alive, other_run, walked, end_step, ncarpet, sum_v, sum_s, bits;
  __m256i looking, look_last, resume, resumed;
};

__attribute__((target("avx2"), always_inline)) inline void set_bounds8(GroupState& st,
                                                                       const GroupConsts& c) {
  st.vl = _mm256_sub_epi32(_mm256_srai_epi32(_mm256_add_epi32(st.vref, c.vstep), 8), c.one);
  st.sl = _mm256_add_epi32(_mm256_srai_epi32(_mm256_sub_epi32(st.sref, c.sstep), 8), c.one);
}

__attribute__((target("avx2"), always_inline)) inline GroupState group_start(const LockLanes& ln,
                                                                             const GroupConsts& c) {
  GroupState st;
  st.vref = load8(ln.vref);
  st.sref = load8(ln.sref);
  set_bounds8(st, c);
  st.alive = _mm256_set1_epi32(-1);
  st.other_run = st.walked = _mm256_setzero_si256();
  st.end_step = _mm256_set1_epi32(-1);
  st.ncarpet = st.sum_v = st.sum_s = st.bits = _mm256_setzero_si256();
  st.looking = st.look_last = st.resume = st.resumed = _mm256_setzero_si256();
  return st;
}

// One step's two pixels per lane: V, S, line (above both bounds) and of the carpet's colour
// (raw: flag and value window, line or not).
struct StepPixels {
  __m256i v0, v1, s0, s1, line0, line1, raw0, raw1;
};

__attribute__((target("avx2"), always_inline)) inline StepPixels classify8(__m256i c0, __m256i c1,
                                                                           const GroupState& st,
                                                                           const GroupConsts& c) {
  StepPixels p;
  p.v0 = _mm256_and_si256(c0, c.m255);
  p.v1 = _mm256_and_si256(c1, c.m255);
  p.s0 = _mm256_and_si256(_mm256_srli_epi32(c0, 8), c.m255);
  p.s1 = _mm256_and_si256(_mm256_srli_epi32(c1, 8), c.m255);
  p.line0 = _mm256_and_si256(_mm256_cmpgt_epi32(p.v0, st.vl), _mm256_cmpgt_epi32(st.sl, p.s0));
  p.line1 = _mm256_and_si256(_mm256_cmpgt_epi32(p.v1, st.vl), _mm256_cmpgt_epi32(st.sl, p.s1));
  p.raw0 = _mm256_and_si256(
      _mm256_and_si256(_mm256_cmpgt_epi32(c0, c.flag_min), _mm256_cmpgt_epi32(p.v0, c.vmin_m1)),
      _mm256_cmpgt_epi32(c.vmax_p1, p.v0));
  p.raw1 = _mm256_and_si256(
      _mm256_and_si256(_mm256_cmpgt_epi32(c1, c.flag_min), _mm256_cmpgt_epi32(p.v1, c.vmin_m1)),
      _mm256_cmpgt_epi32(c.vmax_p1, p.v1));
  return p;
}

// Looking behind an end: any pixel of the carpet's colour makes the bin carpet; a lane stops
// looking when the run is long enough or its last step is reached.
__attribute__((target("avx2"), always_inline)) inline void look_behind8(GroupState& st,
                                                                        const StepPixels& p,
                                                                        __m256i look, __m256i sv,
                                                                        const GroupConsts& c) {
  st.resume = _mm256_blendv_epi8(
      st.resume,
      _mm256_and_si256(_mm256_add_epi32(st.resume, c.one), _mm256_or_si256(p.raw0, p.raw1)), look);
  const __m256i found = _mm256_and_si256(look, _mm256_cmpgt_epi32(st.resume, c.resume_m1));
  st.resumed = _mm256_or_si256(st.resumed, found);
  st.looking = _mm256_and_si256(_mm256_andnot_si256(found, st.looking),
                                _mm256_cmpgt_epi32(st.look_last, sv));
}

// The histogram word of a carpet bin's rounded deviations (dv, ds in Q8): narrow when both lie in
// [-32, 31], wide otherwise; the lane's "none" slot for any other bin.
__attribute__((target("avx2"), always_inline)) inline __m256i hist_word8(__m256i dv, __m256i ds,
                                                                         __m256i carpet,
                                                                         const GroupConsts& c) {
  const __m256i dvr = _mm256_srai_epi32(_mm256_add_epi32(dv, c.c128), 8),
                dsr = _mm256_srai_epi32(_mm256_add_epi32(ds, c.c128), 8);
  const __m256i dv32 = _mm256_add_epi32(dvr, c.c32), ds32 = _mm256_add_epi32(dsr, c.c32);
  const __m256i narrow_ok = _mm256_cmpeq_epi32(
      _mm256_and_si256(_mm256_or_si256(dv32, ds32), c.not63), _mm256_setzero_si256());
  const __m256i narrow = _mm256_or_si256(_mm256_slli_epi32(dv32, 6), ds32);
  // kHistWide | (dv + 255) | (ds + 255) << 12: dv + 255 and ds + 255 lie in 0..510.
  const __m256i wide =
      _mm256_add_epi32(c.wide_bit, _mm256_add_epi32(dvr, _mm256_slli_epi32(dsr, 12)));
  return _mm256_blendv_epi8(c.none_lane, _mm256_blendv_epi8(wide, narrow, narrow_ok), carpet);
}

// The carpet lanes' running means move by alpha of the deviation (a shift when alpha is a power
// of two), the bounds with them; their sums and counts grow.
__attribute__((target("avx2"), always_inline)) inline void move_means8(
    GroupState& st, __m256i carpet, __m256i dv, __m256i ds, __m256i bv, __m256i bs,
    const LockConsts& k, const GroupConsts& c) {
  __m256i step_v, step_s;
  if (k.alpha_shift >= 0) {
    step_v = _mm256_sra_epi32(dv, c.shift);
    step_s = _mm256_sra_epi32(ds, c.shift);
  } else {
    step_v = _mm256_srai_epi32(_mm256_mullo_epi32(dv, c.alpha), 8);
    step_s = _mm256_srai_epi32(_mm256_mullo_epi32(ds, c.alpha), 8);
  }
  st.vref = _mm256_add_epi32(st.vref, _mm256_and_si256(carpet, step_v));
  st.sref = _mm256_add_epi32(st.sref, _mm256_and_si256(carpet, step_s));
  set_bounds8(st, c);
  st.sum_v = _mm256_add_epi32(st.sum_v, _mm256_and_si256(carpet, bv));
  st.sum_s = _mm256_add_epi32(st.sum_s, _mm256_and_si256(carpet, bs));
  st.ncarpet = _mm256_sub_epi32(st.ncarpet, carpet);
}

// The end run: "other" bins in a row; a lane whose run reaches end_run_px ends at this step and
// looks behind it over the steps after this one up to min(bins - 2, end + resume_within_px - 1)
// (a bin counts once its successor is reached within resume_within_px, as walk_fast).
__attribute__((target("avx2"), always_inline)) inline void end_run8(GroupState& st, __m256i other,
                                                                    __m256i sv,
                                                                    const GroupConsts& c) {
  st.other_run = _mm256_and_si256(_mm256_add_epi32(st.other_run, c.one), other);
  const __m256i ended = _mm256_and_si256(other, _mm256_cmpgt_epi32(st.other_run, c.end_run_m1));
  st.end_step = _mm256_blendv_epi8(st.end_step, sv, ended);
  st.alive = _mm256_andnot_si256(ended, st.alive);
  const __m256i last = _mm256_min_epi32(c.bins_m2, _mm256_add_epi32(sv, c.look_reach));
  st.look_last = _mm256_blendv_epi8(st.look_last, last, ended);
  st.looking = _mm256_or_si256(st.looking, _mm256_and_si256(ended, _mm256_cmpgt_epi32(last, sv)));
}

// Step s of the lanes still walking (act) or looking behind their end (look): the bins decided,
// the records written (rec, hist), the means, the end run and the line bits.
__attribute__((target("avx2"), always_inline)) inline void walk_step8(
    GroupState& st, const StepPixels& p, __m256i act, __m256i look, int s, const LockConsts& k,
    const GroupConsts& c, std::uint32_t* rec, std::uint32_t* hist) {
  const __m256i sv = _mm256_set1_epi32(s);
  const __m256i any_line = _mm256_or_si256(p.line0, p.line1);
  // A pixel of the carpet's colour (cp: and not line).
  const __m256i cp0 = _mm256_andnot_si256(p.line0, p.raw0),
                cp1 = _mm256_andnot_si256(p.line1, p.raw1);
  look_behind8(st, p, look, sv, c);
  const __m256i any_cp = _mm256_or_si256(cp0, cp1);
  const __m256i line = _mm256_and_si256(any_line, act);
  const __m256i carpet = _mm256_andnot_si256(any_line, _mm256_and_si256(any_cp, act));
  const __m256i other = _mm256_andnot_si256(_mm256_or_si256(any_line, any_cp), act);
  const __m256i bv = _mm256_blendv_epi8(p.v0, p.v1, cp1), bs = _mm256_blendv_epi8(p.s0, p.s1, cp1);
  const __m256i dv = _mm256_sub_epi32(_mm256_slli_epi32(bv, 8), st.vref),
                ds = _mm256_sub_epi32(_mm256_slli_epi32(bs, 8), st.sref);
  // The bin as seen, before the means move.
  const __m256i line_v = _mm256_and_si256(
      line, _mm256_max_epi32(_mm256_and_si256(p.line0, p.v0), _mm256_and_si256(p.line1, p.v1)));
  const __m256i r =
      _mm256_or_si256(_mm256_or_si256(_mm256_max_epi32(p.v0, p.v1), _mm256_slli_epi32(line_v, 8)),
                      _mm256_slli_epi32(st.vref, 16));
  _mm256_storeu_si256(reinterpret_cast<__m256i*>(rec + 8 * s), r);
  const __m256i h = hist_word8(dv, ds, carpet, c);
  if (k.histogram) _mm256_storeu_si256(reinterpret_cast<__m256i*>(hist + 8 * s), h);
  move_means8(st, carpet, dv, ds, bv, bs, k, c);
  st.walked = _mm256_sub_epi32(st.walked, act);
  end_run8(st, other, sv, c);
  st.bits = _mm256_or_si256(
      st.bits, _mm256_and_si256(line, _mm256_set1_epi32(static_cast<int>(1u << (s & 31)))));
}

// Returns the steps walked (every lane has ended or run out of bins after them).
__attribute__((target("avx2"))) int walk_group_avx2(const std::uint32_t* code,
                                                    const std::int32_t* pixel0,
                                                    const std::int32_t* pixel1, int steps,
                                                    const LockConsts& k, LockLanes& ln,
                                                    std::uint32_t* rec, std::uint32_t* hist,
                                                    std::uint32_t* line_bits) {
  const auto* code_i = reinterpret_cast<const int*>(code);
  const GroupConsts c = group_consts(k, ln);
  GroupState st = group_start(ln, c);
  int s = 0;
  for (; s < steps; ++s) {
    const __m256i sv = _mm256_set1_epi32(s);
    const __m256i act = _mm256_and_si256(st.alive, _mm256_cmpgt_epi32(c.bins, sv));
    const __m256i look = _mm256_andnot_si256(_mm256_cmpgt_epi32(sv, st.look_last), st.looking);
    if (_mm256_testz_si256(_mm256_or_si256(act, look), _mm256_or_si256(act, look))) break;
    const StepPixels p =
        classify8(gather8(code_i, pixel0 + 8 * s), gather8(code_i, pixel1 + 8 * s), st, c);
    walk_step8(st, p, act, look, s, k, c, rec, hist);
    if ((s & 31) == 31) {
      _mm256_storeu_si256(reinterpret_cast<__m256i*>(line_bits + 8 * (s >> 5)), st.bits);
      st.bits = _mm256_setzero_si256();
    }
  }
  if ((s & 31) != 0)
    _mm256_storeu_si256(reinterpret_cast<__m256i*>(line_bits + 8 * (s >> 5)), st.bits);
  store8(ln.walked, st.walked);
  store8(ln.end_step, st.end_step);
  store8(ln.carpet, st.ncarpet);
  store8(ln.sum_v, st.sum_v);
  store8(ln.sum_s, st.sum_s);
  store8(ln.resumed, st.resumed);
  return s;
}
#endif

// The carpet's deviation histograms (which estimate the line steps) are taken from one ray per
// degree: 90 000 carpet bins or so on a frame are as good a sample as 360 000, and at 4 rays per
// degree their counting was a fifth of the extraction's time (bench_frame_path).
inline bool histogram_ray(int j, int rays) {
  return j % std::max(1, rays / kScanRays) == 0;
}

// Robust sigma (1.4826 MAD) of a histogram of integer deviations offset by 255.
double hist_sigma(const std::array<int, 511>& h) {
  long n = 0;
  for (int c : h) n += c;
  if (n == 0) return 0.0;
  auto quantile_bin = [&](const std::array<int, 511>& hh, long total) {
    long acc = 0;
    for (int i = 0; i < 511; ++i) {
      acc += hh[static_cast<std::size_t>(i)];
      if (2 * acc >= total) return i;
    }
    return 510;
  };
  const int med = quantile_bin(h, n);
  std::array<int, 511> dev{};
  for (int i = 0; i < 511; ++i)
    dev[static_cast<std::size_t>(std::abs(i - med))] += h[static_cast<std::size_t>(i)];
  return 1.4826 * quantile_bin(dev, n);
}

// A white run along a ray (consecutive "line" bins): its crossing is placed where it first reaches
// edge_fraction of the way from the carpet to its peak (a blurred edge's foot is brighter than the
// carpet but is not yet the line).
constexpr int kClippedV = 250;  // a V this high may be the sensor's clipping, not the line's level

struct WhiteRun {
  // The ray's bin centres (RayTable::bin_centre from its first bin; null: none known, then a
  // crossing is the first bin at or above the edge level).
  const float* centre = nullptr;
  int centre_first = 0, centre_count = 0;
  bool open = false, counts = false;
  int start = 0, n = 0, peak = 0, before_v = 0, gap_before = 0;
  float floor = 0.0f;
  std::array<std::uint8_t, 32> v{};
  // Bin `bin` is line: opens a run (after `gap` non-line bins) or extends the open one.
  void add(int bin, int line_v, int gap, int min_gap, int prev_bin, int prev_v, int vref_q) {
    if (!open) {
      open = true;
      counts = gap >= min_gap;
      gap_before = gap;
      before_v = prev_bin == bin - 1 ? prev_v : 0;
      start = bin;
      n = 0;
      peak = 0;
      floor = static_cast<float>(vref_q) / 256.0f;
    }
    if (n < static_cast<int>(v.size()))
      v[static_cast<std::size_t>(n++)] = static_cast<std::uint8_t>(line_v);
    peak = std::max(peak, line_v);
  }
  // Closes an open run, writing its crossing to out[found++] when it counts.
  void finish(std::uint8_t* out, int& found, float edge_fraction, int k0, int min_gap) {
    if (!open) return;
    open = false;
    if (!counts || found >= kCrossingsPerRay) return;
    const float half = floor + edge_fraction * (static_cast<float>(peak) - floor);
    // The bin before the run may already be half-way (its pixel failed the saturation step).
    if (static_cast<float>(before_v) >= half && start - 1 >= k0 && gap_before > min_gap) {
      out[found++] = static_cast<std::uint8_t>(start - 1);
      return;
    }
    int k = 0;
    while (k + 1 < n && static_cast<float>(v[static_cast<std::size_t>(k)]) < half) ++k;
    out[found++] =
        static_cast<std::uint8_t>(start + k - (edge_in_bin_before(k, half, k0, min_gap) ? 1 : 0));
  }
  // The database's crossing is the first integer at or beyond the edge (expected_features). Bin b
  // holds the pixel centres in (b - 1, b], so the first bin at the edge level can lie one beyond
  // it: the edge is placed where the level crosses `half`, linearly between the two bins' pixel
  // centres (RayTable::bin_centre), and the crossing is the bin before when the edge is at or below
  // its upper end (the first bin alone put crossings 0.27 px outward on average on rendered
  // frames).
  [[nodiscard]] bool edge_in_bin_before(int k, float half, int k0, int min_gap) const {
    const int b = start + k;
    if (centre == nullptr || b - 1 < centre_first || b - centre_first >= centre_count) return false;
    if (k == 0 && !(b - 1 >= k0 && gap_before > min_gap)) return false;  // the gap rule still holds
    // A clipped peak (over-exposed white) is not the line's level: half of it comes early.
    if (peak >= kClippedV) return false;
    const float vk = static_cast<float>(v[static_cast<std::size_t>(k)]);
    const float vp = k > 0 ? static_cast<float>(v[static_cast<std::size_t>(k - 1)])
                           : (before_v > 0 ? static_cast<float>(before_v) : floor);
    if (!(vk >= half && vp < half && vk > vp)) return false;
    const float cp = centre[b - 1 - centre_first], ck = centre[b - centre_first];
    const float edge = cp + (half - vp) / (vk - vp) * (ck - cp);
    return edge <= static_cast<float>(b - 1) + 1e-4f;
  }
  // A run on ray j of the table (its bin centres).
  static WhiteRun of_ray(const LineExtractor::RayTable& t, int j) {
    WhiteRun run;
    run.on_ray(t, j);
    return run;
  }
  void on_ray(const LineExtractor::RayTable& t, int j) {
    if (!t.bins_ok || t.bin_centre.size() != t.bin_pixel.size()) return;
    const auto a = static_cast<std::size_t>(j);
    centre = t.bin_centre.data() + t.bin_begin[a];
    centre_first = t.first_bin[a];
    centre_count = t.bin_begin[a + 1] - t.bin_begin[a];
  }
};

// Ray j's crossings cleared; nullptr for a hidden ray (marked hidden), else where they go.
std::uint8_t* start_ray(bool hidden, int j, BearingScan& scan, ExtractionReport& rep) {
  std::uint8_t* out = scan.radii_px.data() + static_cast<std::size_t>(j) * kCrossingsPerRay;
  std::fill(out, out + kCrossingsPerRay, kNoCrossing);
  if (hidden) {
    scan.ray_end_px[static_cast<std::size_t>(j)] = kRayHidden;
    rep.carpet_end_px[static_cast<std::size_t>(j)] = 0;
    return nullptr;
  }
  ++rep.rays;
  return out;
}

// A walked ray's outcome: where it ends (its first "other" bin of the end run, end < 0: none),
// whether that is an obstacle (the carpet resumes behind it) or the carpet's end, and its crossings
// below the end (the end is exclusive).
void finish_ray(int end, bool carpet_resumes, int carpet_bins, int k0, const ExtractionParams& x,
                std::uint8_t* out, std::uint8_t& ray_end, std::uint8_t& carpet_end,
                ExtractionReport& rep) {
  if (carpet_bins >= x.carpet_resume_px) ++rep.rays_seen;
  if (end < 0) {
    ray_end = kRayToViewEnd;
    carpet_end = 255;
  } else {
    ray_end = end <= k0 ? kRayHidden : static_cast<std::uint8_t>(end);
    if (carpet_resumes) {
      ++rep.rays_ended_at_obstacle;
      carpet_end = 255;
    } else {
      ++rep.rays_ended_at_carpet_edge;
      carpet_end = static_cast<std::uint8_t>(std::max(end, 1));
    }
  }
  for (int c = 0; c < kCrossingsPerRay; ++c)
    if (out[c] != kNoCrossing && out[c] >= ray_end) out[c] = kNoCrossing;
  for (int c = 0; c < kCrossingsPerRay; ++c) rep.crossings += out[c] != kNoCrossing;
}

// What every ray's walk keeps fixed over a frame: the database's gap rule (expected_features),
// the running mean's weight alpha_q / 256, the line steps in Q8, the end run and the edge rule.
struct WalkRules {
  int min_gap, alpha_q, val_step_q, sat_step_q, end_run_px, k0;
  float edge_fraction;
};

WalkRules walk_rules(const ExtractionParams& x, int val_step, int sat_step, int k0) {
  return {ScanParams{}.min_gap_px,
          std::max(1, static_cast<int>(std::lround(256.0 / x.carpet_mean_px))),
          val_step << 8,
          sat_step << 8,
          x.end_run_px,
          k0,
          static_cast<float>(x.edge_fraction)};
}

// A carpet bin's deviation (Q8) from the running mean as its deviation histogram's bin (rounded,
// offset by 255, clamped to 0..510).
inline std::size_t dev_bin(int d_q) {
  return static_cast<std::size_t>(std::clamp(((d_q + 128) >> 8) + 255, 0, 510));
}

// One ray's walk, bin by bin, as walk_rays and walk_fast make it: the running carpet means in
// 8-bit fixed point (Q8: integer arithmetic on every carpet bin) with the line test as two integer
// bounds recomputed when the means move, the gap since the last line bin, the run of "other" bins
// that ends the ray (end: its first bin, < 0 while none), and the ray's carpet sums for the light.
struct RayWalk {
  int vref_q, sref_q;
  int val_step_q, sat_step_q;
  int v_line_min = 0, s_line_max = 0;
  int gap = 0, other_run = 0, carpet_bins = 0, end = -1;
  int prev_bin = -1, prev_v = 0;  // the last closed bin that was not line, and its brightest pixel
  long sum_v = 0, sum_s = 0, count = 0;

  RayWalk(double sector_val, double sector_sat, const WalkRules& k)
      : vref_q(static_cast<int>(std::lround(256.0 * sector_val))),
        sref_q(static_cast<int>(std::lround(256.0 * sector_sat))),
        val_step_q(k.val_step_q),
        sat_step_q(k.sat_step_q) {
    set_bounds();
  }
  void set_bounds() {
    v_line_min = (vref_q + val_step_q + 255) >> 8;  // ceil
    s_line_max = (sref_q - sat_step_q) >> 8;        // floor (arithmetic shift)
  }
  [[nodiscard]] bool is_line(int v, int s) const { return v >= v_line_min && s <= s_line_max; }
  // A line bin: opens the white run (after the gap) or extends it.
  void line(WhiteRun& run, int bin, int line_v, const WalkRules& k) {
    run.add(bin, line_v, gap, k.min_gap, prev_bin, prev_v, vref_q);
    gap = 0;
    other_run = 0;
  }
  // A bin that is not line (any_v: its brightest pixel) closes the white run, writing its crossing.
  void not_line(WhiteRun& run, std::uint8_t* out, int& found, int bin, int any_v,
                const WalkRules& k) {
    run.finish(out, found, k.edge_fraction, k.k0, k.min_gap);
    prev_bin = bin;
    prev_v = any_v;
    ++gap;
  }
  // A carpet bin (V and S of its last carpet pixel): the means move by step(deviation), the
  // deviations (Q8, before the move) are returned for the histograms.
  template <class Step>
  void carpet(int b_v, int b_s, const Step& step, int& dv_q, int& ds_q) {
    other_run = 0;
    ++carpet_bins;
    dv_q = (b_v << 8) - vref_q;
    ds_q = (b_s << 8) - sref_q;
    vref_q += step(dv_q);
    sref_q += step(ds_q);
    set_bounds();
    sum_v += b_v;
    sum_s += b_s;
    ++count;
  }
  // Another bin: true when it completes the end run (end set to the run's first bin).
  bool other(int bin, int end_run_px) {
    if (++other_run < end_run_px) return false;
    end = bin - other_run + 1;
    return true;
  }
};

// The ray's carpet sums into its sector's (LineExtractor::Frame, private: deduced).
void add_ray_sums(auto& fr, std::size_t sec, const RayWalk& w) {
  fr.sum_v[sec] += static_cast<double>(w.sum_v);
  fr.sum_s[sec] += static_cast<double>(w.sum_s);
  fr.count[sec] += w.count;
}

// The bin of the per-pixel walk being read: whether a pixel of it is line (and the brightest
// such), whether one has the carpet's colour (and the last such pixel's V and S), its brightest
// pixel.
struct PixelBin {
  int bin = -1;
  bool line = false, carpet = false;
  int v = 0, s = 0, line_v = 0, any_v = 0;
  void open(int b) {
    bin = b;
    line = carpet = false;
    line_v = 0;
    any_v = 0;
  }
  void add(int pv, int ps, bool is_line, bool is_carpet) {
    any_v = std::max(any_v, pv);
    if (is_line) {
      line = true;
      line_v = std::max(line_v, pv);
    } else if (is_carpet) {
      carpet = true;
      v = pv;
      s = ps;
    }
  }
};

// Obstacle or the carpet's end (walk_rays): does the carpet resume behind the blob? The table's
// entries from i on, up to resume_within_px bins past the end; a bin counts once its successor's
// first pixel is reached, any carpet pixel (is_carpet(i)) makes it carpet. Returns the run of
// carpet bins found (up to carpet_resume_px).
template <class IsCarpet>
int carpet_run_behind(const LineExtractor::RayTable& t, std::int32_t i, std::int32_t i1, int end,
                      const ExtractionParams& x, const IsCarpet& is_carpet) {
  int resume = 0, cur = -1;
  bool cur_carpet = false;
  const int look_to = end + x.resume_within_px;
  for (; i < i1 && resume < x.carpet_resume_px; ++i) {
    const int bi = t.bin[static_cast<std::size_t>(i)];
    if (bi > look_to) break;
    if (bi != cur) {
      if (cur >= 0) resume = cur_carpet ? resume + 1 : 0;
      cur = bi;
      cur_carpet = false;
    }
    cur_carpet = is_carpet(i) || cur_carpet;
  }
  return resume;
}

// A bin of the code plane as walk_fast reads it: both its pixels' V and S and whether each has the
// carpet's hue and saturation (code_pixels' word: V | S << 8 | carpet hue << 16).
struct CodedBin {
  int v0, s0, v1, s1;
  bool hue0, hue1;
};

inline CodedBin coded_bin(const std::uint32_t* code, const std::int32_t* bp, const std::int16_t* bs,
                          std::int32_t k) {
  const std::uint32_t c0 = code[bp[k]], c1 = code[bp[k] + bs[k]];
  return {static_cast<int>(c0 & 255u),
          static_cast<int>((c0 >> 8) & 255u),
          static_cast<int>(c1 & 255u),
          static_cast<int>((c1 >> 8) & 255u),
          (c0 >> 16) != 0,
          (c1 >> 16) != 0};
}

// Ray j's bins in the table's bin arrays: [b0, b1), the first being bin first_bin of the ray.
struct RayBins {
  std::int32_t b0, b1;
  int first_bin;
};

RayBins ray_bins(const LineExtractor::RayTable& t, int j) {
  const auto a = static_cast<std::size_t>(j);
  return {t.bin_begin[a], t.bin_begin[a + 1], t.first_bin[a]};
}

// The deviation histograms in four interleaved copies (by bin), summed at the end: neighbouring
// carpet bins mostly deviate alike, and one counter incremented back to back stalls on its own
// store.
struct DevHistograms {
  std::array<std::array<int, 512>, 4> v{}, s{};
  void count(int bin, int dv_q, int ds_q) {
    const auto copy = static_cast<std::size_t>(bin & 3);
    ++v[copy][dev_bin(dv_q)];
    ++s[copy][dev_bin(ds_q)];
  }
  void add_to(std::array<int, 511>& dev_v, std::array<int, 511>& dev_s) const {
    for (std::size_t b = 0; b < 511; ++b) {
      dev_v[b] += v[0][b] + v[1][b] + v[2][b] + v[3][b];
      dev_s[b] += s[0][b] + s[1][b] + s[2][b] + s[3][b];
    }
  }
};

// Behind the end (walk_fast): a bin counts once the next one is reached within resume_within_px
// (as the per-pixel walk commits a bin at its successor's first pixel); any carpet pixel makes it
// carpet. Bins from k on; returns the run of carpet bins found (up to carpet_resume_px).
int coded_carpet_run_behind(const std::uint32_t* code, const LineExtractor::RayTable& t,
                            std::int32_t k, const RayBins& r, int end, const ExtractionParams& x,
                            int vmin, int vmax) {
  const std::int32_t b0 = r.b0, b1 = r.b1;
  const int first_bin = r.first_bin;
  const std::int32_t* bp = t.bin_pixel.data();
  const std::int16_t* bs = t.bin_second.data();
  int resume = 0;
  const int look_to = end + x.resume_within_px;
  for (; k + 1 < b1 && resume < x.carpet_resume_px; ++k) {
    if (first_bin + (k + 1 - b0) > look_to) break;
    const CodedBin b = coded_bin(code, bp, bs, k);
    const bool carpet =
        (b.hue0 && b.v0 >= vmin && b.v0 <= vmax) || (b.hue1 && b.v1 >= vmin && b.v1 <= vmax);
    resume = carpet ? resume + 1 : 0;
  }
  return resume;
}

// The running mean's step for a deviation d_q (Q8): alpha_q / 256 of it. The weight is 1/8 for the
// default carpet_mean_px: a shift then replaces the multiply on the walk's serial chain
// (floor((d * 2^a) / 256) = d >> (8 - a)).
struct MeanStep {
  int alpha_q, alpha_shift = -1;
  explicit MeanStep(int alpha) : alpha_q(alpha) {
    for (int a = 0; a <= 8; ++a)
      if (alpha_q == 1 << a) alpha_shift = 8 - a;
  }
  int operator()(int d_q) const {
    return alpha_shift >= 0 ? d_q >> alpha_shift : (d_q * alpha_q) >> 8;
  }
};

// The frame's carpet fraction: carpet bins of the bins walked.
double carpet_fraction(long bins_carpet, long bins_seen) {
  return bins_seen > 0 ? static_cast<double>(bins_carpet) / static_cast<double>(bins_seen) : 0.0;
}

#ifdef OMNILOC_HAVE_X86
// Each sector's starting carpet means in Q8, for the lanes. False when one does not fit the
// record's 16 bits (the mean stays within [0, max(start, 255 * 256)]).
bool lane_start_means(const std::vector<double>& sector_val, const std::vector<double>& sector_sat,
                      std::vector<std::int32_t>& vref0, std::vector<std::int32_t>& sref0) {
  const std::size_t sectors = sector_val.size();
  vref0.assign(sectors, 0);
  sref0.assign(sectors, 0);
  for (std::size_t k = 0; k < sectors; ++k) {
    const long v = std::lround(256.0 * sector_val[k]), sat = std::lround(256.0 * sector_sat[k]);
    if (v < 0 || v > 65535 || sat < -65535 || sat > 65535) return false;
    vref0[k] = static_cast<std::int32_t>(v);
    sref0[k] = static_cast<std::int32_t>(sat);
  }
  return true;
}

// The lockstep walk's constants for a frame (walk_fast's rules, the look behind an end).
LockConsts lock_consts(const ExtractionParams& x, const WalkRules& k, bool histogram) {
  LockConsts kc;
  kc.val_step_q = k.val_step_q;
  kc.sat_step_q = k.sat_step_q;
  kc.end_run_px = x.end_run_px;
  kc.carpet_resume_px = x.carpet_resume_px;
  kc.histogram = histogram;
  kc.resume_within_px = x.resume_within_px;
  kc.alpha_q = k.alpha_q;
  kc.alpha_shift = MeanStep(k.alpha_q).alpha_shift;
  return kc;
}

// What the lockstep walk writes per step and lane, for the longest group of the table, and the
// narrow histogram in a copy per lane (neighbouring rays deviate alike at the same step, and
// back-to-back increments of one counter wait on each other).
struct LockRecords {
  std::vector<std::uint32_t> rec, hist, line_bits;
  std::vector<std::array<int, kHistNone + 8>> narrow =
      std::vector<std::array<int, kHistNone + 8>>(8);
  explicit LockRecords(const LineExtractor::RayTable& t) {
    int max_steps = 0;
    for (std::size_t g = 0; g + 1 < t.lock_begin.size(); ++g)
      max_steps = std::max(max_steps, t.lock_begin[g + 1] - t.lock_begin[g]);
    const auto words = static_cast<std::size_t>(8 * (max_steps + 32));
    rec.assign(words, 0);
    hist.assign(words, 0);
    line_bits.assign(words / 32 + 8, 0);
  }
};

// Group g's lanes: each ray's bins, its sector's starting means and value window (a lane without
// a ray: sector 0's). (LineExtractor::Frame, private: deduced.)
void load_lanes(LockLanes& ln, const LineExtractor::RayTable& t, std::size_t g,
                const std::vector<std::int32_t>& vref0, const std::vector<std::int32_t>& sref0,
                const auto& fr) {
  for (std::size_t l = 0; l < 8; ++l) {
    const int j = t.lock_ray[8 * g + l];
    const auto sec =
        j < 0 ? std::size_t{0} : static_cast<std::size_t>(t.sector[static_cast<std::size_t>(j)]);
    ln.bins[l] = t.lock_bins[8 * g + l];
    ln.vref[l] = vref0[sec];
    ln.sref[l] = sref0[sec];
    ln.vmin[l] = fr.vmin[sec];
    ln.vmax[l] = fr.vmax[sec];
  }
}

// The group's deviation histograms, from the lanes whose rays sample them: a wide word straight
// into the frame's, a narrow one into its lane's copy.
void count_lane_histograms(auto& fr, LockRecords& rc, const LineExtractor::RayTable& t,
                           std::size_t g, int ran, int n) {
  for (std::size_t l = 0; l < 8; ++l) {
    const int j = t.lock_ray[8 * g + l];
    if (j < 0 || !histogram_ray(j, n)) continue;
    for (int st = 0; st < ran; ++st) {
      const std::uint32_t w = rc.hist[8 * static_cast<std::size_t>(st) + l];
      if ((w & kHistWide) != 0) {
        ++fr.dev_v[w & 4095u];
        ++fr.dev_s[(w >> 12) & 4095u];
      } else {
        ++rc.narrow[l][w];
      }
    }
  }
}

// Lane l's crossings (ray j, `walked` bins): the white runs from the line bins it recorded, as
// walk_fast makes them. Returns how many were written to out.
int lane_crossings(std::uint8_t* out, const LineExtractor::RayTable& t, int j, std::size_t l,
                   int walked, const LockRecords& rc, const WalkRules& k) {
  const int first_bin = t.first_bin[static_cast<std::size_t>(j)];
  WhiteRun run;
  run.on_ray(t, j);
  int found = 0, last = -1;
  for (int w = 0; 32 * w < walked; ++w) {
    for (std::uint32_t m = rc.line_bits[8 * static_cast<std::size_t>(w) + l]; m != 0; m &= m - 1) {
      const int st = 32 * w + __builtin_ctz(m);
      const std::uint32_t r = rc.rec[8 * static_cast<std::size_t>(st) + l];
      const int line_v = static_cast<int>((r >> 8) & 255u), vref_q = static_cast<int>(r >> 16);
      if (run.open && st != last + 1) run.finish(out, found, k.edge_fraction, k.k0, k.min_gap);
      if (!run.open) {
        const int prev_v =
            st > 0 ? static_cast<int>(rc.rec[8 * static_cast<std::size_t>(st - 1) + l] & 255u) : 0;
        run.add(first_bin + st, line_v, st - last - 1, k.min_gap, st > 0 ? first_bin + st - 1 : -1,
                prev_v, vref_q);
      } else {
        run.add(first_bin + st, line_v, 0, k.min_gap, -1, 0, vref_q);
      }
      last = st;
    }
  }
  run.finish(out, found, k.edge_fraction, k.k0, k.min_gap);
  return found;
}

// The lanes' narrow histogram copies into the frame's: word (dv + 32) * 64 + ds + 32.
void merge_narrow(auto& fr, const LockRecords& rc) {
  for (int a = 0; a < 64; ++a) {
    for (int b = 0; b < 64; ++b) {
      const auto at = static_cast<std::size_t>(a * 64 + b);
      int c = 0;
      for (const auto& copy : rc.narrow) c += copy[at];
      fr.dev_v[static_cast<std::size_t>(a - 32 + 255)] += c;
      fr.dev_s[static_cast<std::size_t>(b - 32 + 255)] += c;
    }
  }
}
#endif

}  // namespace

// Per-frame working state: the thresholds used and what the walk measured for the adaptation.
struct LineExtractor::Frame {
  std::vector<int> vmin, vmax;       // per sector carpet value window
  std::vector<double> sum_v, sum_s;  // per sector, carpet bins
  std::vector<long> count;
  std::array<int, 511> dev_v{}, dev_s{};  // carpet bin minus the running carpet mean
  int sat_min = 0;
  int val_step = 0, sat_step = 0;
};

LineExtractor::LineExtractor(const CameraModel& cam)
    : width_px_(cam.width_px),
      height_px_(cam.height_px),
      cx_(cam.center_px.x()),
      cy_(cam.center_px.y()),
      yaw_offset_deg_(cam.yaw_offset_deg),
      mirrored_(cam.mirrored),
      step_px_(cam.scan_step_px()),
      k0_(cam.first_scan_sample()),
      k1_(cam.last_scan_sample()),
      vision_(cam.vision),
      tables_(kMaxRaysPerDegree + 1),
      carpet_(cam.vision.carpet_hsv),
      contrast_(cam.vision.line_contrast) {
  for (const auto& m : cam.masts) masts_.emplace_back(m.bearing_deg, m.half_width_deg);
  if (carpet_) ref_val_ = 0.5 * (carpet_->val_min + carpet_->val_max);
}

// The pixels each ray touches, in order: a 4-connected path (a diagonal step gets the neighbour
// nearer the ray inserted), so that no 1 px line, whatever its direction, lies between two
// consecutive pixels. Each pixel is binned at the sample at or beyond its centre's distance along
// the ray (a camera whose samples are more than 1 px apart puts several pixels in a bin: a line
// between two samples is still seen).
const LineExtractor::RayTable& LineExtractor::table(int rpd, std::size_t step_bytes) {
  RayTable& t = tables_[static_cast<std::size_t>(rpd)];
  if (!t.begin.empty() && t.step_bytes == static_cast<int>(step_bytes)) return t;
  t = RayTable{};
  t.step_bytes = static_cast<int>(step_bytes);
  t.row_u0.assign(static_cast<std::size_t>(height_px_), width_px_);
  t.row_u1.assign(static_cast<std::size_t>(height_px_), -1);
  const int n = kScanRays * rpd;
  const int sectors = vision_.extraction.sectors;
  t.begin.reserve(static_cast<std::size_t>(n) + 1);
  for (int j = 0; j < n; ++j) {
    t.begin.push_back(static_cast<std::int32_t>(t.offset.size()));
    const double bearing = static_cast<double>(j) / rpd;
    bool hidden = false;
    for (const auto& [b, w] : masts_) hidden = hidden || std::abs(angle_diff_deg(bearing, b)) <= w;
    t.hidden.push_back(hidden);
    t.sector.push_back(static_cast<std::uint8_t>(std::min(sectors - 1, j * sectors / n)));
    if (hidden) continue;
    const double phi = deg_to_rad(bearing + yaw_offset_deg_);
    const double du = std::cos(phi) * (mirrored_ ? -1.0 : 1.0), dv = -std::sin(phi);
    int pu = -1, pv = -1;
    auto emit = [&](int u, int v) {
      if (u < 0 || v < 0 || u >= width_px_ || v >= height_px_) return;
      const double along = ((u - cx_) * du + (v - cy_) * dv) / step_px_;
      // The sample convention of the database (expected_features): a crossing at the first integer
      // radius at or beyond the line's edge, so a pixel counts at the integer at or above its
      // centre.
      const int bin = static_cast<int>(std::ceil(along - 1e-9));
      if (bin < k0_ || bin > k1_) return;
      t.offset.push_back(static_cast<std::int32_t>(v * static_cast<long>(step_bytes) + 3L * u));
      t.bin.push_back(static_cast<std::uint8_t>(bin));
      t.along.push_back(static_cast<float>(along));
      t.pixel.push_back(v * width_px_ + u);
      t.row_u0[static_cast<std::size_t>(v)] = std::min(t.row_u0[static_cast<std::size_t>(v)], u);
      t.row_u1[static_cast<std::size_t>(v)] = std::max(t.row_u1[static_cast<std::size_t>(v)], u);
    };
    for (double r = k0_ * step_px_ - 0.5; r <= k1_ * step_px_ + 0.5; r += 0.05) {
      const int u = static_cast<int>(std::floor(cx_ + r * du + 0.5)),
                v = static_cast<int>(std::floor(cy_ + r * dv + 0.5));
      if (u == pu && v == pv) continue;
      if (pu >= 0 && u != pu && v != pv) {
        // Diagonal step: the corner pixel whose centre is nearer the ray line.
        const double da = std::abs((u - cx_) * dv - (pv - cy_) * du),
                     db = std::abs((pu - cx_) * dv - (v - cy_) * du);
        if (da <= db)
          emit(u, pv);
        else
          emit(pu, v);
      }
      emit(u, v);
      pu = u;
      pv = v;
    }
  }
  t.begin.push_back(static_cast<std::int32_t>(t.offset.size()));
  bin_layout(t, n);
  return t;
}

// The fast walk's layout: a ray's bins are consecutive integers of one or two pixels each (a
// 4-connected step advances at most 1 px along the ray, two steps at least 1 px), so each bin is
// stored as its first pixel and the offset to its second (0 when it has one: reading a pixel twice
// changes neither a maximum, nor "any", nor "the last one"). A table where that does not hold
// (none is known) keeps the per-pixel walk.
void LineExtractor::bin_layout(RayTable& t, int n) const {
  t.bins_ok = true;
  t.bin_begin.assign(1, 0);
  t.first_bin.assign(static_cast<std::size_t>(n), 0);
  for (int j = 0; j < n && t.bins_ok; ++j) {
    const std::int32_t i0 = t.begin[static_cast<std::size_t>(j)],
                       i1 = t.begin[static_cast<std::size_t>(j) + 1];
    if (i0 < i1) t.first_bin[static_cast<std::size_t>(j)] = t.bin[static_cast<std::size_t>(i0)];
    for (std::int32_t i = i0; i < i1;) {
      const auto k = static_cast<std::size_t>(i);
      const bool pair = i + 1 < i1 && t.bin[k + 1] == t.bin[k];
      const int next = i + (pair ? 2 : 1);
      if (next < i1 && t.bin[static_cast<std::size_t>(next)] != t.bin[k] + 1)
        t.bins_ok = false;  // three in a bin or a gap
      if (pair && std::abs(t.pixel[k + 1] - t.pixel[k]) > 32767)
        t.bins_ok = false;  // a row wider than int16
      t.bin_pixel.push_back(t.pixel[k]);
      t.bin_second.push_back(static_cast<std::int16_t>(pair ? t.pixel[k + 1] - t.pixel[k] : 0));
      t.bin_centre.push_back(pair ? std::max(t.along[k], t.along[k + 1]) : t.along[k]);
      i = next;
    }
    t.bin_begin.push_back(static_cast<std::int32_t>(t.bin_pixel.size()));
  }
  if (!t.bins_ok) return;
  t.lock_begin.assign(1, 0);
  std::vector<int> rays;
  for (int j = 0; j < n; ++j)
    if (!t.hidden[static_cast<std::size_t>(j)]) rays.push_back(j);
  for (std::size_t g = 0; g < rays.size(); g += 8) {
    int steps = 0;
    for (std::size_t l = 0; l < 8; ++l) {
      const int j = g + l < rays.size() ? rays[g + l] : -1;
      const int bins = j < 0 ? 0
                             : t.bin_begin[static_cast<std::size_t>(j) + 1] -
                                   t.bin_begin[static_cast<std::size_t>(j)];
      t.lock_ray.push_back(j);
      t.lock_bins.push_back(bins);
      steps = std::max(steps, bins);
    }
    for (int st = 0; st < steps; ++st) {
      for (std::size_t l = 0; l < 8; ++l) {
        const std::size_t lane = g + l;
        std::int32_t p0 = 0, p1 = 0;
        if (lane < rays.size() && st < t.lock_bins[lane]) {
          const auto k =
              static_cast<std::size_t>(t.bin_begin[static_cast<std::size_t>(rays[lane])] + st);
          p0 = t.bin_pixel[k];
          p1 = p0 + t.bin_second[k];
        }
        t.lock_pixel0.push_back(p0);
        t.lock_pixel1.push_back(p1);
      }
    }
    t.lock_begin.push_back(t.lock_begin.back() + steps);
  }
}

// The carpet colour from the frame when the camera has none: the colour cluster that reaches out
// from the robot's body on most bearings of the view (estimate_carpet_colour; the camera gives the
// body and the view's end, so no ring or colour is assumed).
bool LineExtractor::ensure_carpet(const cv::Mat& bgr, std::string* why) {
  if (carpet_) return true;
  CarpetSearch search;
  search.centre_px = {cx_, cy_};
  search.inner_px = k0_ * step_px_;
  search.outer_px = k1_ * step_px_;
  const auto c = estimate_carpet_colour(bgr, search, why);
  if (!c) return false;
  if (!(c->median_val >= 1.0)) {  // the light follows the carpet's brightness: a black one has none
    *why = "no carpet: the floor around the robot is black (median brightness " +
           std::to_string(c->median_val) + ")";
    return false;
  }
  // A line is brighter than the carpet by at least min_val_step: a carpet at the sensor's top (the
  // frame blown out) leaves no room for one.
  if (c->median_val > 255.0 - vision_.extraction.min_val_step) {
    *why = "no carpet: the floor around the robot is overexposed (median brightness " +
           std::to_string(static_cast<int>(std::lround(c->median_val))) + ")";
    return false;
  }
  carpet_ = CarpetHsv{c->hue, c->hue_half_width, c->sat_min, c->val_min, c->val_max};
  ref_val_ = c->median_val;
  sector_val_.clear();
  return true;
}

// The walk of every ray, whatever gives each pixel's values: px(i, vmin, vmax, v, s) sets table
// entry i's V and S and says whether it has the carpet's colour within the value window [vmin,
// vmax].
template <class Pixel>
void LineExtractor::walk_rays(const RayTable& t, BearingScan& scan, ExtractionReport& rep,
                              Frame& fr, Pixel px) const {
  const ExtractionParams& x = vision_.extraction;
  const WalkRules k = walk_rules(x, fr.val_step, fr.sat_step, k0_);
  const auto step = [alpha_q = k.alpha_q](int d_q) { return (d_q * alpha_q) >> 8; };
  const int n = static_cast<int>(t.hidden.size());
  long bins_seen = 0, bins_carpet = 0;
  for (int j = 0; j < n; ++j) {
    std::uint8_t* out = start_ray(t.hidden[static_cast<std::size_t>(j)], j, scan, rep);
    if (out == nullptr) continue;
    const bool sampled = histogram_ray(j, n);
    const auto sec = static_cast<std::size_t>(t.sector[static_cast<std::size_t>(j)]);
    const int vmin = fr.vmin[sec], vmax = fr.vmax[sec];
    RayWalk w(sector_val_[sec], sector_sat_[sec], k);
    WhiteRun run = WhiteRun::of_ray(t, j);
    int found = 0;
    PixelBin b;
    // One bin decided: crossing (line entry after the gap), carpet (updates the running mean), or
    // other.
    auto close_bin = [&]() {
      ++bins_seen;
      if (b.line) return w.line(run, b.bin, b.line_v, k);
      w.not_line(run, out, found, b.bin, b.any_v, k);
      if (!b.carpet) return (void)w.other(b.bin, k.end_run_px);
      ++bins_carpet;
      int dv_q = 0, ds_q = 0;
      w.carpet(b.v, b.s, step, dv_q, ds_q);
      if (sampled) {
        ++fr.dev_v[dev_bin(dv_q)];
        ++fr.dev_s[dev_bin(ds_q)];
      }
    };
    const std::int32_t i1 = t.begin[static_cast<std::size_t>(j) + 1];
    std::int32_t i = t.begin[static_cast<std::size_t>(j)];
    for (; i < i1; ++i) {
      const int bi = t.bin[static_cast<std::size_t>(i)];
      if (bi != b.bin) {
        if (b.bin >= 0) {
          close_bin();
          if (w.end >= 0) break;
        }
        b.open(bi);
      }
      int v, s;
      const bool carpet = px(i, vmin, vmax, v, s);
      b.add(v, s, w.is_line(v, s), carpet);
    }
    if (w.end < 0 && b.bin >= 0) close_bin();
    run.finish(out, found, k.edge_fraction, k.k0, k.min_gap);
    add_ray_sums(fr, sec, w);
    const int resume = w.end < 0 ? 0 : carpet_run_behind(t, i, i1, w.end, x, [&](std::int32_t e) {
      int v, s;
      return px(e, vmin, vmax, v, s);
    });
    finish_ray(w.end, resume >= x.carpet_resume_px, w.carpet_bins, k0_, x, out,
               scan.ray_end_px[static_cast<std::size_t>(j)],
               rep.carpet_end_px[static_cast<std::size_t>(j)], rep);
  }
  rep.carpet_fraction = carpet_fraction(bins_carpet, bins_seen);
}

// Reference: every pixel converted from BGR on every ray that touches it (OpenCV's integer HSV).
void LineExtractor::walk(const cv::Mat& bgr, const RayTable& t, BearingScan& scan,
                         ExtractionReport& rep, Frame& fr) const {
  const int* sdiv = detail::hsv_tables().sat_div;
  const int* hdiv = detail::hsv_tables().hue_div;
  const int sat_min = fr.sat_min;
  walk_rays(t, scan, rep, fr, [&](std::int32_t i, int vmin, int vmax, int& v, int& s) {
    const std::uint8_t* p = bgr.data + t.offset[static_cast<std::size_t>(i)];
    v = std::max({p[0], p[1], p[2]});
    const int diff = v - std::min({p[0], p[1], p[2]});
    s = (diff * sdiv[v] + (1 << 11)) >> 12;
    return s >= sat_min && v >= vmin && v <= vmax &&
           hue_ok_[static_cast<std::size_t>(hue_of(p, v, diff, hdiv))];
  });
}

// Each pixel any ray touches, converted once per frame into code_ (rows in memory order): near the
// centre several rays share a pixel, and the walk then reads one word instead of three bytes and a
// hue.
void LineExtractor::code_pixels(const cv::Mat& bgr, const RayTable& t, int sat_min) {
  const int* sdiv = detail::hsv_tables().sat_div;
  const int* hdiv = detail::hsv_tables().hue_div;
  code_.resize(static_cast<std::size_t>(width_px_) * static_cast<std::size_t>(height_px_));
  for (int row = 0; row < height_px_; ++row) {
    const int u0 = t.row_u0[static_cast<std::size_t>(row)],
              u1 = t.row_u1[static_cast<std::size_t>(row)];
    const std::uint8_t* p = bgr.ptr<std::uint8_t>(row) + 3 * u0;
    std::uint32_t* out =
        code_.data() + static_cast<std::size_t>(row) * static_cast<std::size_t>(width_px_);
    for (int u = u0; u <= u1; ++u, p += 3) {
      const int v = std::max({p[0], p[1], p[2]});
      const int diff = v - std::min({p[0], p[1], p[2]});
      const int s = (diff * sdiv[v] + (1 << 11)) >> 12;
      const bool carpet_hue =
          s >= sat_min && hue_ok_[static_cast<std::size_t>(hue_of(p, v, diff, hdiv))];
      out[u] = static_cast<std::uint32_t>(v) | static_cast<std::uint32_t>(s) << 8 |
               static_cast<std::uint32_t>(carpet_hue) << 16;
    }
  }
}

// code_pixels, 8 pixels at a time with AVX2 (the scalar loop for the last few of a row); false
// when the CPU has no AVX2 (nothing converted).
bool LineExtractor::code_pixels_avx2(const cv::Mat& bgr, const RayTable& t, int sat_min) {
#ifdef OMNILOC_HAVE_X86
  if (!cpu_has_avx2() || !hsv_divisors_match()) return false;
  HueRanges hue;
  if (!hue_ranges(hue_ok_, hue)) return false;
  code_.resize(static_cast<std::size_t>(width_px_) * static_cast<std::size_t>(height_px_));
  code_rows_avx2(bgr, t.row_u0.data(), t.row_u1.data(), code_.data(), hue, sat_min);
  return true;
#else
  (void)bgr;
  (void)t;
  (void)sat_min;
  return false;
#endif
}

// walk_fast's decisions for 8 rays at a time (walk_group_avx2), then per ray the white runs from
// the line bins it recorded, the look behind an end and finish_ray as in walk_fast. False (nothing
// walked) without AVX2 or when a sector's carpet level does not fit the record's 16 bits.
bool LineExtractor::walk_lockstep(const RayTable& t, BearingScan& scan, ExtractionReport& rep,
                                  Frame& fr) const {
#ifdef OMNILOC_HAVE_X86
  const ExtractionParams& x = vision_.extraction;
  if (!cpu_has_avx2() || t.lock_begin.size() < 2 || x.carpet_resume_px < 1 ||
      x.resume_within_px < 1)
    return false;
  std::vector<std::int32_t> vref0, sref0;
  if (!lane_start_means(sector_val_, sector_sat_, vref0, sref0)) return false;
  const WalkRules k = walk_rules(x, fr.val_step, fr.sat_step, k0_);
  // adapt() reads the histograms only to estimate the steps.
  const LockConsts kc = lock_consts(x, k, !vision_.line_contrast);
  const int n = static_cast<int>(t.hidden.size());
  for (int j = 0; j < n; ++j)
    if (t.hidden[static_cast<std::size_t>(j)]) (void)start_ray(true, j, scan, rep);
  LockRecords rc(t);
  long bins_seen = 0, bins_carpet = 0;
  LockLanes ln;
  for (std::size_t g = 0; g + 1 < t.lock_begin.size(); ++g) {
    load_lanes(ln, t, g, vref0, sref0, fr);
    const std::int32_t first = t.lock_begin[g], steps = t.lock_begin[g + 1] - first;
    const int ran =
        walk_group_avx2(code_.data(), t.lock_pixel0.data() + 8 * static_cast<std::size_t>(first),
                        t.lock_pixel1.data() + 8 * static_cast<std::size_t>(first), steps, kc, ln,
                        rc.rec.data(), rc.hist.data(), rc.line_bits.data());
    if (kc.histogram) count_lane_histograms(fr, rc, t, g, ran, n);
    for (std::size_t l = 0; l < 8; ++l) {
      const int j = t.lock_ray[8 * g + l];
      if (j < 0) continue;
      std::uint8_t* out = start_ray(false, j, scan, rep);
      (void)lane_crossings(out, t, j, l, ln.walked[l], rc, k);
      const auto sec = static_cast<std::size_t>(t.sector[static_cast<std::size_t>(j)]);
      bins_seen += ln.walked[l];
      bins_carpet += ln.carpet[l];
      fr.sum_v[sec] += static_cast<double>(ln.sum_v[l]);
      fr.sum_s[sec] += static_cast<double>(ln.sum_s[l]);
      fr.count[sec] += ln.carpet[l];
      const int first_bin = t.first_bin[static_cast<std::size_t>(j)];
      const int end = ln.end_step[l] >= 0 ? first_bin + ln.end_step[l] - x.end_run_px + 1 : -1;
      finish_ray(end, ln.resumed[l] != 0, ln.carpet[l], k.k0, x, out,
                 scan.ray_end_px[static_cast<std::size_t>(j)],
                 rep.carpet_end_px[static_cast<std::size_t>(j)], rep);
    }
  }
  merge_narrow(fr, rc);
  rep.carpet_fraction = carpet_fraction(bins_carpet, bins_seen);
  return true;
#else
  (void)t;
  (void)scan;
  (void)rep;
  (void)fr;
  return false;
#endif
}

// As walk_rays, bin by bin: both pixels of a bin read and combined without branches, the same
// decisions in the same order (WhiteRun, the look behind an end and finish_ray as in walk_rays).
void LineExtractor::walk_fast(const RayTable& t, BearingScan& scan, ExtractionReport& rep,
                              Frame& fr) const {
  const ExtractionParams& x = vision_.extraction;
  const std::uint32_t* code = code_.data();
  // Read once: the histograms' int stores could alias the parameters' ints, forcing reloads.
  const WalkRules k = walk_rules(x, fr.val_step, fr.sat_step, k0_);
  const MeanStep step(k.alpha_q);
  const int n = static_cast<int>(t.hidden.size());
  long bins_seen = 0, bins_carpet = 0;
  DevHistograms hist;  // four interleaved copies
  const std::int32_t* bp = t.bin_pixel.data();
  const std::int16_t* bs = t.bin_second.data();
  for (int j = 0; j < n; ++j) {
    std::uint8_t* out = start_ray(t.hidden[static_cast<std::size_t>(j)], j, scan, rep);
    if (out == nullptr) continue;
    const bool sampled = histogram_ray(j, n);
    const auto sec = static_cast<std::size_t>(t.sector[static_cast<std::size_t>(j)]);
    const int vmin = fr.vmin[sec], vmax = fr.vmax[sec];
    RayWalk w(sector_val_[sec], sector_sat_[sec], k);
    WhiteRun run = WhiteRun::of_ray(t, j);
    int found = 0;
    const RayBins r = ray_bins(t, j);
    std::int32_t kb = r.b0;
    for (; kb < r.b1; ++kb) {
      const int bin = r.first_bin + (kb - r.b0);
      const CodedBin c = coded_bin(code, bp, bs, kb);
      const bool line0 = w.is_line(c.v0, c.s0), line1 = w.is_line(c.v1, c.s1);
      const bool carpet1 = !line1 && c.hue1 && c.v1 >= vmin && c.v1 <= vmax;
      const bool carpet0 = !line0 && c.hue0 && c.v0 >= vmin && c.v0 <= vmax;
      ++bins_seen;
      if (line0 || line1) {
        w.line(run, bin, std::max(line0 ? c.v0 : 0, line1 ? c.v1 : 0), k);
        continue;
      }
      w.not_line(run, out, found, bin, std::max(c.v0, c.v1), k);
      if (carpet0 || carpet1) {
        ++bins_carpet;
        int dv_q = 0, ds_q = 0;  // the bin's last carpet pixel
        w.carpet(carpet1 ? c.v1 : c.v0, carpet1 ? c.s1 : c.s0, step, dv_q, ds_q);
        if (sampled) hist.count(bin, dv_q, ds_q);
      } else if (w.other(bin, k.end_run_px)) {
        ++kb;
        break;
      }
    }
    run.finish(out, found, k.edge_fraction, k.k0, k.min_gap);
    add_ray_sums(fr, sec, w);
    const int resume =
        w.end < 0 ? 0 : coded_carpet_run_behind(code, t, kb, r, w.end, x, vmin, vmax);
    finish_ray(w.end, resume >= x.carpet_resume_px, w.carpet_bins, k.k0, x, out,
               scan.ray_end_px[static_cast<std::size_t>(j)],
               rep.carpet_end_px[static_cast<std::size_t>(j)], rep);
  }
  hist.add_to(fr.dev_v, fr.dev_s);
  rep.carpet_fraction = carpet_fraction(bins_carpet, bins_seen);
}

// Follows the light: each sector's carpet level moves light_follow of the way to this frame's mean
// (bounded to light_range of the reference), and estimated line steps follow the carpet's spread.
void LineExtractor::adapt(const Frame& fr) {
  const ExtractionParams& x = vision_.extraction;
  for (std::size_t k = 0; k < sector_val_.size(); ++k) {
    if (fr.count[k] == 0) continue;
    const double v = fr.sum_v[k] / static_cast<double>(fr.count[k]),
                 s = fr.sum_s[k] / static_cast<double>(fr.count[k]);
    sector_val_[k] = std::clamp(sector_val_[k] + x.light_follow * (v - sector_val_[k]),
                                ref_val_ / x.light_range, ref_val_ * x.light_range);
    sector_sat_[k] += x.light_follow * (s - sector_sat_[k]);
  }
  if (!vision_.line_contrast) {
    LineContrast seen{std::max(x.val_sigmas * hist_sigma(fr.dev_v), x.min_val_step),
                      std::max(x.sat_sigmas * hist_sigma(fr.dev_s), x.min_sat_step)};
    // A grey carpet's saturation is noise: its lines are told by brightness alone.
    if (carpet_ && is_grey_carpet(carpet_->hue_half_width)) seen.sat_step = 0.0;
    if (!contrast_) {
      contrast_ = seen;
    } else {
      contrast_->val_step += x.light_follow * (seen.val_step - contrast_->val_step);
      contrast_->sat_step += x.light_follow * (seen.sat_step - contrast_->sat_step);
    }
  }
}

// An end well inside where the neighbouring rays end is an obstacle even when the carpet does not
// resume behind it (a robot or a person hides the floor behind it up to the view's end).
void LineExtractor::mark_tall_obstacles(const BearingScan& scan, ExtractionReport& rep) const {
  const ExtractionParams& x = vision_.extraction;
  const int n = static_cast<int>(scan.ray_end_px.size());
  const int w = static_cast<int>(std::lround(x.obstacle_window_deg * scan.rays_per_degree));
  auto reach = [&](int j) {
    const int e = scan.ray_end_px[static_cast<std::size_t>((j % n + n) % n)];
    return e == kRayToViewEnd ? k1_ + 1 : e;
  };
  std::vector<int> around;
  for (int j = 0; j < n; ++j) {
    std::uint8_t& ce = rep.carpet_end_px[static_cast<std::size_t>(j)];
    const int e = scan.ray_end_px[static_cast<std::size_t>(j)];
    if (e == kRayHidden || e == kRayToViewEnd || ce == 255)
      continue;  // hidden, open or already an obstacle
    around.clear();
    for (int d = -w; d <= w;
         d += scan.rays_per_degree)  // one ray per degree is enough for a median
      if (scan.ray_end_px[static_cast<std::size_t>(((j + d) % n + n) % n)] != kRayHidden)
        around.push_back(reach(j + d));
    std::nth_element(around.begin(),
                     around.begin() + static_cast<std::ptrdiff_t>(around.size() / 2), around.end());
    if (e + x.obstacle_step_px <= around[around.size() / 2]) {
      ce = 255;
      --rep.rays_ended_at_carpet_edge;
      ++rep.rays_ended_at_obstacle;
    }
  }
}

// As mark_tall_obstacles, with the window's median kept in a sliding histogram per ray residue
// (the window of ray j + rays_per_degree is ray j's shifted by one ray per degree) instead of
// collected and partially sorted per ray: the median is at least e + obstacle_step_px exactly when
// fewer than half (index size / 2) of the window's reaches are below that.
void LineExtractor::mark_tall_obstacles_fast(const BearingScan& scan, ExtractionReport& rep) const {
  const ExtractionParams& x = vision_.extraction;
  const int n = static_cast<int>(scan.ray_end_px.size()), rpd = scan.rays_per_degree;
  const int w = static_cast<int>(std::lround(x.obstacle_window_deg * rpd));
  const int m = 2 * w / rpd + 1;  // window rays: j - w + i * rpd, i = 0 .. m - 1
  const std::uint8_t* end = scan.ray_end_px.data();
  auto at = [&](int j) { return ((j % n) + n) % n; };
  for (int r = 0; r < rpd; ++r) {
    std::array<int, 256> fine{};
    std::array<int, 16> coarse{};
    int size = 0;
    auto add = [&](int j, int delta) {
      const int e = end[at(j)];
      if (e == kRayHidden) return;
      const int reach = e == kRayToViewEnd ? k1_ + 1 : e;
      fine[static_cast<std::size_t>(reach)] += delta;
      coarse[static_cast<std::size_t>(reach >> 4)] += delta;
      size += delta;
    };
    for (int i = 0; i < m; ++i) add(r - w + i * rpd, 1);
    for (int j = r; j < n; j += rpd) {
      if (j > r) {
        add(j - rpd - w, -1);
        add(j - w + (m - 1) * rpd, 1);
      }
      std::uint8_t& ce = rep.carpet_end_px[static_cast<std::size_t>(j)];
      const int e = end[j];
      if (e == kRayHidden || e == kRayToViewEnd || ce == 255 || size == 0) continue;
      const int limit = std::min(e + x.obstacle_step_px, 256);
      int below = 0;
      for (int c = 0; c < limit >> 4; ++c) below += coarse[static_cast<std::size_t>(c)];
      for (int v = limit & ~15; v < limit; ++v) below += fine[static_cast<std::size_t>(v)];
      if (below <= size / 2) {
        ce = 255;
        --rep.rays_ended_at_carpet_edge;
        ++rep.rays_ended_at_obstacle;
      }
    }
  }
}

BearingScan LineExtractor::extract(const cv::Mat& bgr, int rpd, ExtractionReport* report) {
  return extract_impl(bgr, rpd, report, Walk::kFast);
}

BearingScan LineExtractor::extract_reference(const cv::Mat& bgr, int rpd,
                                             ExtractionReport* report) {
  return extract_impl(bgr, rpd, report, Walk::kReference);
}

BearingScan LineExtractor::extract_with(Walk how, const cv::Mat& bgr, int rpd,
                                        ExtractionReport* report) {
  return extract_impl(bgr, rpd, report, how);
}

// A frame the followed state cannot read (too little carpet, too few rays or crossings) is read
// again, with the same carpet window, before it is given up, with the light per sector and
// the estimated line steps measured on this frame alone (the first frame's two passes). The
// followed state can be stale: a light switched on near the robot, or the exposure jumping, makes
// the carpet brighter than the running reference by more than a line's step, and carpet taken for
// line never updates that reference. When even that finds too little carpet (the light jumped
// beyond what the window follows), an estimated carpet is estimated again from this frame. A carpet
// estimated from a frame that gives nothing usable is not kept: the next frame estimates again.
BearingScan LineExtractor::extract_impl(const cv::Mat& bgr, int rpd, ExtractionReport* report,
                                        Walk how) {
  ExtractionReport local;
  ExtractionReport& rep = report != nullptr ? *report : local;
  const bool followed = !sector_val_.empty();
  bool estimated_here = !carpet_.has_value();
  const std::optional<CarpetHsv> carpet = carpet_;
  const double ref_val = ref_val_;
  BearingScan scan = extract_once(bgr, rpd, &rep, how);
  if (rep.usable) return scan;
  if (followed && carpet) {
    carpet_ = carpet;  // too little carpet dropped an estimated one: it is tried once more first
    ref_val_ = ref_val;
    sector_val_.clear();
    contrast_ = vision_.line_contrast;
    scan = extract_once(bgr, rpd, &rep, how);
  }
  if (!rep.usable && carpet && !carpet_ && !vision_.carpet_hsv) {
    // Too little carpet even in this frame's own light: the light jumped beyond what the window
    // follows (light_range); the carpet is estimated again from this frame.
    estimated_here = true;
    scan = extract_once(bgr, rpd, &rep, how);
  }
  if (!rep.usable && estimated_here && !vision_.carpet_hsv && carpet_) {
    carpet_.reset();
    sector_val_.clear();
    contrast_ = vision_.line_contrast;
  }
  return scan;
}

namespace {

// The frame must be what the camera model describes, and the ray count in range: a wrong image
// would walk rays off its edge.
void check_extract_input(const cv::Mat& bgr, int rpd, int width_px, int height_px) {
  if (bgr.empty()) throw std::invalid_argument("extract: empty image");
  if (bgr.type() != CV_8UC3)
    throw std::invalid_argument("extract: image must be 8-bit BGR (CV_8UC3), got type " +
                                std::to_string(bgr.type()));
  if (bgr.cols != width_px || bgr.rows != height_px) {
    throw std::invalid_argument("extract: image is " + std::to_string(bgr.cols) + " x " +
                                std::to_string(bgr.rows) + " but the camera model expects " +
                                std::to_string(width_px) + " x " + std::to_string(height_px));
  }
  if (rpd < 1 || rpd > kMaxRaysPerDegree)
    throw std::invalid_argument("extract: rays_per_degree must be 1..20, got " +
                                std::to_string(rpd));
}

// A scan of n rays with no crossings, every ray hidden until walked.
BearingScan empty_scan(int rpd, int n) {
  BearingScan scan;
  scan.rays_per_degree = rpd;
  scan.radii_px.assign(static_cast<std::size_t>(n) * kCrossingsPerRay, kNoCrossing);
  scan.ray_end_px.assign(static_cast<std::size_t>(n), kRayHidden);
  return scan;
}

// Which of OpenCV's 180 hues are the carpet's (within its half width, round the circle).
std::array<bool, 180> carpet_hues(const CarpetHsv& carpet) {
  std::array<bool, 180> ok{};
  for (int i = 0; i < 180; ++i) {
    const double dh = std::abs(i - carpet.hue);
    ok[static_cast<std::size_t>(i)] = std::min(dh, 180.0 - dh) <= carpet.hue_half_width;
  }
  return ok;
}

// The code plane pays when the rays touch more pixels than it converts (4 rays per degree: 2x;
// at 1 ray per degree the rays skip most pixels beyond ~60 px and the scalar per-pixel walk is
// cheaper). With AVX2 it always pays: the plane converts 8 pixels at a time and the lockstep walk
// needs it (2 rays per degree, 1280 x 1024: 1.0 ms with it, 1.8 ms without, bench_frame_path).
// (The walk is private to LineExtractor: the caller says whether it is the reference or the fast
// one.)
bool code_plane_pays(const LineExtractor::RayTable& t, bool reference_walk, bool fast_walk) {
  long plane_px = 0;
  for (std::size_t row = 0; row < t.row_u0.size(); ++row)
    plane_px += std::max(0, t.row_u1[row] - t.row_u0[row] + 1);
  return !reference_walk && t.bins_ok &&
         (static_cast<long>(t.pixel.size()) >= plane_px || (fast_walk && cpu_has_avx2()));
}

// A pass's thresholds: each sector's carpet value window scaled by its light, the saturation
// floor and the line steps (LineExtractor::Frame, private: deduced).
void start_frame(auto& fr, std::size_t sectors, const std::vector<double>& sector_val,
                 double ref_val, const CarpetHsv& carpet, const LineContrast& c) {
  fr.vmin.resize(sectors);
  fr.vmax.resize(sectors);
  for (std::size_t k = 0; k < sectors; ++k) {
    const double f = sector_val[k] / ref_val;
    fr.vmin[k] = static_cast<int>(std::floor(carpet.val_min * f));
    fr.vmax[k] = static_cast<int>(std::ceil(std::min(255.0, carpet.val_max * f)));
  }
  fr.sum_v.assign(sectors, 0.0);
  fr.sum_s.assign(sectors, 0.0);
  fr.count.assign(sectors, 0);
  fr.sat_min = static_cast<int>(std::ceil(carpet.sat_min));
  fr.val_step = std::max(1, static_cast<int>(std::lround(c.val_step)));
  fr.sat_step = static_cast<int>(std::lround(c.sat_step));
}

// Obstacle blobs: neighbouring rays ended on the carpet at similar radii (a blob through ray 0
// is joined with the one ending at the last ray).
void group_obstacles(const BearingScan& scan, int n, ExtractionReport& rep) {
  for (int j = 0; j < n; ++j) {
    const auto e = scan.ray_end_px[static_cast<std::size_t>(j)];
    const bool obstacle = e != kRayHidden && e != kRayToViewEnd &&
                          rep.carpet_end_px[static_cast<std::size_t>(j)] == 255;
    if (!obstacle) continue;
    if (!rep.obstacles.empty()) {
      ObstacleBlob& b = rep.obstacles.back();
      const int prev = (b.last_ray + 1) % n;
      const auto pe = scan.ray_end_px[static_cast<std::size_t>(b.last_ray)];
      if (prev == j && std::abs(static_cast<int>(e) - static_cast<int>(pe)) <= std::max(4, e / 8)) {
        b.last_ray = j;
        b.near_radius_px = std::min(b.near_radius_px, static_cast<int>(e));
        continue;
      }
    }
    rep.obstacles.push_back({j, j, static_cast<int>(e)});
  }
  if (rep.obstacles.size() > 1 && rep.obstacles.back().last_ray == n - 1 &&
      rep.obstacles.front().first_ray == 0) {
    rep.obstacles.front().first_ray = rep.obstacles.back().first_ray;  // wraps through ray 0
    rep.obstacles.front().near_radius_px =
        std::min(rep.obstacles.front().near_radius_px, rep.obstacles.back().near_radius_px);
    rep.obstacles.pop_back();
  }
}

// Why the frame is not usable (rep.reason; empty: usable) of the `total` rays not hidden.
// Returns true when too little of the view is carpet.
bool judge_frame(const ExtractionParams& x, int total, ExtractionReport& rep) {
  if (rep.carpet_fraction < x.min_carpet_fraction) {
    rep.reason =
        "no carpet: " + std::to_string(static_cast<int>(std::lround(100 * rep.carpet_fraction))) +
        " % of the view is carpet (at least " +
        std::to_string(static_cast<int>(std::lround(100 * x.min_carpet_fraction))) + " % needed)";
    return true;
  }
  if (rep.rays_seen < x.min_rays_seen * total) {
    rep.reason = "too few rays see the carpet: " + std::to_string(rep.rays_seen) + " of " +
                 std::to_string(total);
  } else if (rep.crossings < x.min_crossings) {
    rep.reason = "too few line crossings: " + std::to_string(rep.crossings) + " (at least " +
                 std::to_string(x.min_crossings) + ")";
  }
  return false;
}

}  // namespace

BearingScan LineExtractor::extract_once(const cv::Mat& bgr, int rpd, ExtractionReport* report,
                                        Walk how) {
  check_extract_input(bgr, rpd, width_px_, height_px_);
  ExtractionReport local;
  ExtractionReport& rep = report != nullptr ? *report : local;
  rep = ExtractionReport{};
  const int n = kScanRays * rpd;
  BearingScan scan = empty_scan(rpd, n);
  rep.carpet_end_px.assign(static_cast<std::size_t>(n), 0);
  rep.carpet_estimated = !vision_.carpet_hsv;
  if (!ensure_carpet(bgr, &rep.reason)) return scan;
  const ExtractionParams& x = vision_.extraction;
  const auto sectors = static_cast<std::size_t>(x.sectors);
  const bool first = sector_val_.size() != sectors;
  if (first) {
    sector_val_.assign(sectors, ref_val_);
    // Before any frame: the middle of the saturation range above sat_min (measured by pass one).
    sector_sat_.assign(sectors, 0.5 * (carpet_->sat_min + 255.0));
  }
  hue_ok_ = carpet_hues(*carpet_);
  const RayTable& t = table(rpd, bgr.step[0]);
  const bool coded = code_plane_pays(t, how == Walk::kReference, how == Walk::kFast);
  if (coded) {
    const int sat_min = static_cast<int>(std::ceil(carpet_->sat_min));
    if (how == Walk::kBinWalk || !code_pixels_avx2(bgr, t, sat_min)) code_pixels(bgr, t, sat_min);
  }
  // The first frame is walked twice: once to measure the light and the carpet's spread, then with
  // them.
  for (int pass = first ? 0 : 1; pass < 2; ++pass) {
    Frame fr;
    const LineContrast c = contrast_.value_or(LineContrast{});
    start_frame(fr, sectors, sector_val_, ref_val_, *carpet_, c);
    rep = ExtractionReport{};
    rep.carpet_end_px.assign(static_cast<std::size_t>(n), 0);
    rep.carpet_estimated = !vision_.carpet_hsv;
    rep.contrast = c;
    if (coded) {
      if (how == Walk::kBinWalk || !walk_lockstep(t, scan, rep, fr)) walk_fast(t, scan, rep, fr);
    } else {
      walk(bgr, t, scan, rep, fr);
    }
    const double keep = vision_.extraction.light_follow;
    if (pass == 0) vision_.extraction.light_follow = 1.0;  // the first measurement is taken whole
    adapt(fr);
    vision_.extraction.light_follow = keep;
  }
  rep.carpet = *carpet_;
  if (how != Walk::kReference)
    mark_tall_obstacles_fast(scan, rep);
  else
    mark_tall_obstacles(scan, rep);
  group_obstacles(scan, n, rep);
  const int total = n - static_cast<int>(std::count(t.hidden.begin(), t.hidden.end(), true));
  if (judge_frame(x, total, rep) && rep.carpet_estimated) {
    carpet_.reset();  // estimated from something else: estimate again on the next frame
    sector_val_.clear();
  }
  rep.usable = rep.reason.empty();
  return scan;
}

}  // namespace omniloc
