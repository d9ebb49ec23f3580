// Each closed-form signal against a Bloch propagation of the magnetization (hard pulses, exact
// relaxation, cycle after cycle to the steady state), over TR, TE, TI and flip angle including
// the extremes; and the contrasts a reader expects of the head at 1.5 T and 3 T, with the shipped
// head's own T2w and FLAIR.

#include "mri/signal_equations.hpp"
#include "mri/tissue_parameters.hpp"
#include "scene/scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

using namespace phantasm;

namespace {

SequenceSettings sequence(SequenceKind kind, double TR, double TE, double flip = 90.0, double TI = 0.0) {
  SequenceSettings s;
  s.kind = kind;
  s.TR_ms = TR;
  s.TE_ms = TE;
  s.flip_deg = flip;
  s.TI_ms = TI;
  return s;
}

const Relaxation k_tissues[] = {
    {0.7, 810, 80, 53},      // white matter, 3 T
    {1.0, 4300, 2000, 100},  // CSF
    {0.05, 302, 0.25, 0.29}, // cortical bone: T2 -> 0
    {0.9, 200, 150, 100},    // T2 close to T1
};

void expect_bloch_agrees(const SequenceSettings& s) {
  for (const Relaxation& r : k_tissues) {
    const double closed = sequence_signal(s, r);
    const double bloch = bloch_signal(s, r);
    EXPECT_NEAR(closed, bloch, 1e-6 * r.PD) << "TR " << s.TR_ms << " TE " << s.TE_ms << " flip " << s.flip_deg
                                            << " TI " << s.TI_ms << " T1 " << r.T1_ms;
  }
}

} // namespace

TEST(SignalEquations, SpinEchoMatchesBloch) {
  for (double TR : {50.0, 600.0, 4000.0, 50000.0}) // 50 s >> every T1
    for (double TE : {0.0, 15.0, 100.0})
      expect_bloch_agrees(sequence(SequenceKind::spin_echo, TR, std::min(TE, 0.5 * TR)));
}

TEST(SignalEquations, SpoiledGradientEchoMatchesBloch) {
  for (double TR : {5.0, 20.0, 2000.0, 50000.0})
    for (double flip : {0.0, 9.0, 30.0, 90.0, 180.0})
      for (double TE : {0.0, 4.0})
        expect_bloch_agrees(sequence(SequenceKind::spoiled_gre, TR, std::min(TE, TR), flip));
}

TEST(SignalEquations, InversionRecoveryMatchesBlochWithBothReadouts) {
  for (Readout readout : {Readout::gradient_echo, Readout::spin_echo}) {
    for (double TI : {10.0, 560.0, 2500.0}) {
      for (double TE : {0.0, 20.0, 120.0}) {
        SequenceSettings s = sequence(SequenceKind::inversion_recovery, 9000.0, TE, 90.0, TI);
        s.readout = readout;
        expect_bloch_agrees(s);
      }
    }
  }
}

TEST(SignalEquations, BalancedSsfpMatchesBloch) {
  for (double TR : {3.0, 5.0, 10.0})
    for (double flip : {0.0, 10.0, 45.0, 90.0, 180.0})
      expect_bloch_agrees(sequence(SequenceKind::bssfp, TR, 0.5 * TR, flip));
}

TEST(SignalEquations, MprageMatchesBloch) {
  for (double flip : {0.0, 9.0, 20.0}) {
    for (double TI : {400.0, 900.0, 1100.0}) {
      SequenceSettings s = sequence(SequenceKind::mprage, 2300.0, 2.98, flip, TI);
      s.echo_spacing_ms = 7.1;
      s.turbo_factor = 64;
      expect_bloch_agrees(s);
    }
  }
}

// T1-weighted (MPRAGE) orders WM > GM > CSF and T2-weighted (spin echo) CSF > GM > WM, with the
// shipped tissue table at both field strengths.
TEST(SignalEquations, HeadContrastsAtOnePointFiveAndThreeTesla) {
  for (double field : {1.5, 3.0}) {
    SCOPED_TRACE(field);
    MriSettings mri;
    mri.field_strength_T = field;
    std::vector<OrganNesting> organs;
    for (const char* tissue : {"white_matter", "gray_matter", "csf"})
      organs.push_back({tissue, tissue, ""});
    const auto parameters = resolve_tissue_parameters(mri, OrganTable(organs));
    auto relaxation = [&](const char* tissue) {
      const TissueParameters& p = parameters.at(tissue);
      return Relaxation{*p.PD, *p.T1_ms, *p.T2_ms, p.T2star_ms ? *p.T2star_ms : *p.T2_ms};
    };
    SequenceSettings t1 = sequence(SequenceKind::mprage, 2300.0, 2.98, 9.0, 900.0);
    t1.echo_spacing_ms = 7.1;
    t1.turbo_factor = 176;
    const SequenceSettings t2 = sequence(SequenceKind::spin_echo, 4000.0, 100.0);
    auto signal = [&](const SequenceSettings& s, const char* tissue) {
      return std::abs(sequence_signal(s, relaxation(tissue)));
    };
    EXPECT_GT(signal(t1, "white_matter"), signal(t1, "gray_matter"));
    EXPECT_GT(signal(t1, "gray_matter"), signal(t1, "csf"));
    EXPECT_GT(signal(t2, "csf"), signal(t2, "gray_matter"));
    EXPECT_GT(signal(t2, "gray_matter"), signal(t2, "white_matter"));
  }
}

// The shipped head's T2w and FLAIR (data-synthetic/head.yaml) with the tissue table, at both
// field strengths: FLAIR shows grey matter brighter than white matter and nulls CSF below both,
// and T2w's white/grey ratio is in the range of real images (about 0.6-0.75; grey matter's T2 is
// about 1.3 times white matter's in vivo).
TEST(SignalEquations, ShippedHeadT2wAndFlairShowGreyWhiteContrast) {
  SceneLoadResult loaded = load_scene(std::string(PHANTASM_SOURCE_DIR) + "/data-synthetic/head.yaml");
  ASSERT_TRUE(loaded.scene);
  Scene& scene = *loaded.scene;
  auto find = [&](const char* name) -> const SequenceSettings& {
    for (const SequenceSettings& s : scene.mri.sequences)
      if (s.name == name) return s;
    throw std::runtime_error(std::string("head.yaml has no sequence ") + name);
  };
  const SequenceSettings& t2 = find("T2w");
  const SequenceSettings& flair = find("FLAIR");
  ASSERT_EQ(t2.kind, SequenceKind::spin_echo);
  ASSERT_EQ(flair.kind, SequenceKind::inversion_recovery);
  for (double field : {1.5, 3.0}) {
    SCOPED_TRACE(field);
    scene.mri.field_strength_T = field;
    const auto parameters = resolve_tissue_parameters(scene.mri, scene.organs);
    auto signal = [&](const SequenceSettings& s, const char* tissue) {
      const TissueParameters& p = parameters.at(tissue);
      return std::abs(sequence_signal(s, {*p.PD, *p.T1_ms, *p.T2_ms, *p.T2_ms}));
    };
    const double white_over_grey = signal(t2, "white_matter") / signal(t2, "gray_matter");
    EXPECT_GT(white_over_grey, 0.6);
    EXPECT_LT(white_over_grey, 0.75);
    EXPECT_GT(signal(flair, "gray_matter"), 1.2 * signal(flair, "white_matter"));
    EXPECT_LT(signal(flair, "csf"), 0.5 * signal(flair, "white_matter"));
  }
}
