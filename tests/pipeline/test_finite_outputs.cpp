// The last check before a dataset is written (#44 item 5): a NaN or an infinity anywhere the
// dataset would hold it is refused, named by its array, voxel and tissue.
#include "pipeline/finite_outputs.hpp"

#include "core/error.hpp"

#include <gtest/gtest.h>

#include <limits>

using namespace phantasm;

namespace {

/// A 2 x 2 x 1 grid: voxels 1 and 2 of gray_matter (label 1), 0 and 3 background; one T1w image
/// per state, finite.
struct SmallRun {
  SequenceSettings sequence;
  Simulation simulation;

  SmallRun() {
    sequence.name = "T1w";
    VoxelizedPhantom& v = simulation.volumes;
    v.grid.dims = Eigen::Vector3i(2, 2, 1);
    v.tissues = {"gray_matter"};
    v.reference.labels = {0, 1, 1, 0};
    v.reference.label_tissues = {-1, 0};
    v.reference.tissue_count = 1;
    v.deformed = v.reference;
    v.deformed->labels = {1, 1, 0, 0};
    MotionFields m;
    m.ref_to_def.assign(12, 0.0f);
    m.def_to_ref.assign(12, 0.0f);
    m.jacobian.assign(4, 1.0f);
    m.def_to_ref_jacobian.assign(4, 1.0f);
    v.motion = m;
    simulation.images.reference.push_back(MrImage{&sequence, {0.0f, 1.0f, 2.0f, 0.0f}, 0.0});
    simulation.images.deformed.push_back(MrImage{&sequence, {1.0f, 2.0f, 0.0f, 0.0f}, 0.0});
  }
};

std::string refusal(const Simulation& simulation) {
  try {
    require_finite_outputs(simulation);
  } catch (const InputError& error) {
    return error.what();
  }
  return "";
}

} // namespace

TEST(FiniteOutputs, AFiniteRunPasses) {
  const SmallRun run;
  EXPECT_NO_THROW(require_finite_outputs(run.simulation));
}

TEST(FiniteOutputs, ANaNImageIsNamedBySequenceStateVoxelAndTissue) {
  SmallRun run;
  run.simulation.images.reference[0].magnitude[2] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(refusal(run.simulation),
            "sequence T1w, reference image: expected finite values before anything is "
            "written, found NaN at voxel (0, 1, 0), tissue gray_matter");
  SmallRun deformed;
  deformed.simulation.images.deformed[0].magnitude[3] = std::numeric_limits<float>::infinity();
  EXPECT_EQ(refusal(deformed.simulation),
            "sequence T1w, deformed image: expected finite values before anything "
            "is written, found inf at voxel (1, 1, 0), tissue background");
}

TEST(FiniteOutputs, FieldsJacobiansMapsLandmarksAndBodiesAreChecked) {
  {
    SmallRun run;
    run.simulation.volumes.motion->def_to_ref[2 * 4 + 1] = std::numeric_limits<float>::quiet_NaN();
    EXPECT_EQ(
        refusal(run.simulation),
        "displacement field from-ref_to-def: expected finite values before anything is written, found NaN "
        "at voxel (1, 0, 0), tissue gray_matter, component 2");
  }
  {
    SmallRun run;
    run.simulation.volumes.motion->jacobian[0] = -std::numeric_limits<float>::infinity();
    EXPECT_NE(refusal(run.simulation).find("Jacobian of from-def_to-ref: "), std::string::npos);
  }
  {
    SmallRun run;
    ParameterMaps maps;
    maps.PD.assign(4, 1.0f);
    maps.T1_ms = {1.0f, std::numeric_limits<float>::quiet_NaN(), 1.0f, 1.0f};
    maps.T2_ms = maps.PD;
    maps.T2star_ms = maps.PD;
    run.simulation.images.reference_maps = maps;
    EXPECT_NE(refusal(run.simulation).find("T1 map of the reference state: "), std::string::npos);
  }
  {
    SmallRun run;
    Landmark landmark;
    landmark.name = "ball_centre";
    landmark.organ = "ball";
    landmark.deformed_mm.x() = std::numeric_limits<double>::quiet_NaN();
    run.simulation.volumes.landmarks.push_back(landmark);
    EXPECT_NE(refusal(run.simulation).find("landmark ball_centre of organ ball: expected finite"),
              std::string::npos);
  }
  {
    SmallRun run;
    PhantomDeformation deformation;
    DeformedBody body;
    body.organ = "ball";
    body.rest_mm = Eigen::MatrixX3d::Zero(2, 3);
    body.deformed_mm = body.rest_mm;
    body.deformed_mm(1, 2) = std::numeric_limits<double>::infinity();
    deformation.bodies.push_back(body);
    run.simulation.deformation = deformation;
    EXPECT_NE(refusal(run.simulation).find("simulated body ball: expected finite vertex positions"),
              std::string::npos);
  }
}
