// The registry template (core/registry.hpp) and the solver registry on it: every solver is a
// member with its own name, help and cost rate, parsed, checked and recorded from the member, and
// an entry point that solves as the member's solver does.

#include "core/registry.hpp"
#include "scene/scene.hpp"
#include "scene/scene_json.hpp"
#include "sim/local_global.hpp"
#include "sim/newton.hpp"
#include "sim/position_based.hpp"
#include "sim/prepared_solver.hpp"
#include "sim/solver_type.hpp"
#include "sim/twisting_bar.hpp"

#include <gtest/gtest.h>

#include <set>
#include <stdexcept>

using namespace phantasm;

namespace {

enum class Colour { red, green, blue };
struct Paint {
  Colour colour;
  const char* name;
};
const Paint k_red{Colour::red, "red"}, k_green{Colour::green, "green"}, k_blue{Colour::blue, "blue"};

struct Unnamed {
  Colour colour;
};

const std::string k_scene = R"(phantasm: 1
name: ball
seed: 7
field_strength_T: 3.0
grid:
  field_of_view_mm: 64
  voxel_size_mm: [2, 2, 4]
anatomy:
  organs:
    - name: ball
      tissue: white_matter
      shape: {type: ellipsoid, center_mm: [0, 0, 0], radii_mm: 20}
)";

std::string scene_with_solver(const std::string& method) {
  return k_scene + "deformation: {mode: dynamic, solver: {method: " + method + "}}\n";
}

/// The solve the member's solver makes when called directly, for comparison with its entry point.
SolveReport direct_solve(SolverMethod method, const TwistingBarStep& bar, Eigen::MatrixX3d& p,
                         const StopCriteria& stop) {
  const auto from_prediction = [&] {
    for (Eigen::Index v = 0; v < p.rows(); ++v)
      if (!bar.model.fixed[static_cast<std::size_t>(v)]) p.row(v) = bar.inertia.target_m.row(v);
  };
  switch (method) {
  case SolverMethod::local_global:
    return LocalGlobalSolver(bar.model, bar.inertia.weight).solve(p, bar.inertia.target_m, stop);
  case SolverMethod::jacobi_chebyshev:
    return LocalGlobalSolver(bar.model, bar.inertia.weight)
        .solve_jacobi_chebyshev(p, bar.inertia.target_m, stop);
  case SolverMethod::newton: return newton_solve(bar.model, bar.inertia, p, stop);
  case SolverMethod::xpbd:
    from_prediction();
    return position_based_solve(PositionBasedVariant::xpbd, bar.model, bar.inertia, p, stop);
  case SolverMethod::gauss_seidel_pbd:
    from_prediction();
    return position_based_solve(PositionBasedVariant::gauss_seidel_pbd, bar.model, bar.inertia, p, stop);
  }
  throw std::logic_error("a solver method this test does not know");
}

} // namespace

TEST(Registry, FindsMembersByKeyAndNameAndListsTheirNamesInOrder) {
  const Registry<Paint, Colour> paints("paint", &Paint::colour, {&k_red, &k_green, &k_blue});
  EXPECT_EQ(&paints.at(Colour::green), &k_green);
  EXPECT_EQ(paints.find("blue"), &k_blue);
  EXPECT_EQ(paints.find("Blue"), nullptr);
  EXPECT_EQ(paints.find(""), nullptr);
  EXPECT_EQ(paints.names(), (std::vector<std::string>{"red", "green", "blue"}));
  EXPECT_EQ(paints.all_names_text(), "red, green or blue");
  EXPECT_EQ(paints.all_names_text(", "), "red, green, blue");
  EXPECT_EQ(paints.names_text([](const Paint& p) { return p.colour != Colour::green; }), "red or blue");
  EXPECT_EQ(paints.names_text([](const Paint& p) { return p.colour == Colour::green; }), "green");
  const Registry<Paint, Colour> one("paint", &Paint::colour, {&k_red});
  EXPECT_THROW(one.at(Colour::blue), std::logic_error);
}

TEST(Registry, RefusesTwoMembersOfOneNameOrOneKey) {
  const Paint other_red{Colour::blue, "red"};
  const Paint other_green{Colour::green, "lime"};
  EXPECT_THROW((Registry<Paint, Colour>("paint", &Paint::colour, {&k_red, &k_green, &other_red})),
               std::logic_error);
  try {
    Registry<Paint, Colour>("paint", &Paint::colour, {&k_red, &k_green, &other_green});
    ADD_FAILURE() << "two members of one key accepted";
  } catch (const std::logic_error& error) {
    EXPECT_EQ(std::string(error.what()), "two members of the paint registry of one kind: green and lime");
  }
  const Unnamed first{Colour::red}, second{Colour::red}, third{Colour::blue};
  EXPECT_THROW((Registry<Unnamed, Colour>("unnamed", &Unnamed::colour, {&first, &second})), std::logic_error);
  const Registry<Unnamed, Colour> unnamed("unnamed", &Unnamed::colour, {&first, &third});
  EXPECT_EQ(&unnamed.at(Colour::blue), &third);
}

TEST(SolverRegistry, EveryMemberHasItsOwnNameMethodHelpCostAndEntryPoint) {
  const auto& types = solver_types();
  const auto& entries = sim_detail::solver_entries();
  ASSERT_EQ(types.size(), entries.size());
  std::set<std::string> names;
  std::set<int> methods;
  for (std::size_t i = 0; i < types.size(); ++i) {
    const SolverType& type = *types[i];
    EXPECT_TRUE(names.insert(type.name).second) << type.name;
    EXPECT_TRUE(methods.insert(static_cast<int>(type.method)).second) << type.name;
    EXPECT_EQ(&solver_type(type.method), &type);
    EXPECT_EQ(find_solver_type(type.name), &type);
    EXPECT_STREQ(to_string(type.method), type.name);
    EXPECT_GT(std::string(type.description).size(), 10u) << type.name;
    EXPECT_GT(type.seconds_per_shell_triangle_step, 0.0) << type.name;
    EXPECT_EQ(entries[i]->method, type.method) << type.name;
    EXPECT_NE(entries[i]->make, nullptr) << type.name;
  }
  EXPECT_EQ(solver_type_names().size(), types.size());
  EXPECT_EQ(find_solver_type("conjugate_gradient"), nullptr);
}

// Each member's name parses into its method, and provenance records the name.
TEST(SolverRegistry, EveryMemberRoundTripsThroughTheSceneAndProvenance) {
  for (const SolverType* type : solver_types()) {
    const SceneLoadResult result = parse_scene(scene_with_solver(type->name), "scene.yaml");
    ASSERT_TRUE(result.scene) << type->name << ": " << format_diagnostics(result.problems);
    EXPECT_EQ(result.scene->deformation.solver.method, type->method) << type->name;
    EXPECT_EQ(scene_settings_json(*result.scene)["deformation"]["solver"]["method"], type->name);
  }
}

TEST(SolverRegistry, AnUnknownNameIsRefusedWithTheListOfMembers) {
  const SceneLoadResult result = parse_scene(scene_with_solver("conjugate_gradient"), "scene.yaml");
  ASSERT_FALSE(result.scene);
  ASSERT_EQ(result.problems.size(), 1u);
  std::string list;
  for (const SolverType* type : solver_types())
    list += (list.empty() ? "" : ", ") + std::string(type->name);
  EXPECT_NE(result.problems.front().format().find("deformation.solver.method: expected one of " + list +
                                                  ", found 'conjugate_gradient'"),
            std::string::npos)
      << result.problems.front().format();
}

// A member that steps in time is refused in a quasi-static scene, and named among the others'
// alternatives when it does not.
TEST(SolverRegistry, OnlyMembersThatStepInTimeAreRefusedInAQuasiStaticScene) {
  const std::string alternatives = static_solver_names();
  for (const SolverType* type : solver_types()) {
    const std::string text =
        k_scene + "deformation: {mode: quasi_static, solver: {method: " + type->name + "}, fixed: [ball]}\n";
    const SceneLoadResult result = parse_scene(text, "scene.yaml");
    EXPECT_EQ(result.scene.has_value(), !type->steps_in_time) << type->name;
    EXPECT_EQ(alternatives.find(type->name) != std::string::npos, !type->steps_in_time)
        << type->name << " in '" << alternatives << "'";
    if (type->steps_in_time) {
      ASSERT_EQ(result.problems.size(), 1u) << type->name;
      EXPECT_NE(
          result.problems.front().format().find("expected " + alternatives + " for a quasi_static scene"),
          std::string::npos)
          << result.problems.front().format();
    }
  }
}

// The entry point of each member solves as its solver does when called directly: the same
// positions, bit for bit, and the report carries the member's name.
TEST(SolverRegistry, EveryEntryPointSolvesAsItsMembersSolver) {
  TwistingBarSettings settings;
  settings.cells = {2, 2, 4};
  settings.size_mm = {40, 40, 80};
  const TwistingBarStep bar = twisting_bar_step(settings);
  StopCriteria stop;
  stop.max_iterations = 5;
  for (const SolverType* type : solver_types()) {
    Eigen::MatrixX3d direct = bar.start_m;
    const SolveReport expected = direct_solve(type->method, bar, direct, stop);
    SolverSettings solver;
    solver.method = type->method;
    Eigen::MatrixX3d p = bar.start_m;
    const auto prepared = sim_detail::solver_entry(type->method).make(bar.model, bar.inertia.weight, solver);
    const SolveReport report = prepared->solve(bar.model, bar.inertia, p, stop);
    EXPECT_EQ(report.solver, std::string(type->name));
    EXPECT_EQ(report.iterations, expected.iterations) << type->name;
    EXPECT_TRUE(p.allFinite()) << type->name;
    EXPECT_EQ((p - direct).cwiseAbs().maxCoeff(), 0.0) << type->name;
    EXPECT_GT((p - bar.start_m).cwiseAbs().maxCoeff(), 0.0) << type->name << " moved nothing";
  }
}
