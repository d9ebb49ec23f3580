#include "anatomy/shape_source.hpp"
#include "core/format.hpp"
#include "core/tissue_table.hpp"
#include "mri/sequence_type.hpp"
#include "scene/parse_sections.hpp"
#include "sim/load_type.hpp"
#include "sim/solver_type.hpp"

#include <algorithm>
#include <cmath>
#include <set>

namespace phantasm::scene_detail {
namespace {

std::string indexed(const std::string& list, std::size_t i, const std::string& key) {
  return list + "[" + std::to_string(i) + "]" + (key.empty() ? "" : "." + key);
}

class ConsistencyChecker {
public:
  ConsistencyChecker(YamlContext& context, const Scene& scene) : m_context(context), m_scene(scene) {}

  void problem(const std::string& key_path, const std::string& message) {
    m_context.problem(m_scene.location_of(key_path), key_path, message);
  }

  void check_grid() {
    const GridSettings& g = m_scene.grid;
    std::int64_t total = 1;
    for (int a = 0; a < 3; ++a) {
      const double count = std::round(g.field_of_view_mm[a] / g.voxel_size_mm[a]);
      if (count < 1.0) {
        problem("grid.voxel_size_mm", "expected voxels no larger than the field of view (" +
                                          format_number(g.field_of_view_mm[a]) + " mm), found " +
                                          format_number(g.voxel_size_mm[a]) + " mm");
        return;
      }
      if (count > 4096.0) {
        problem("grid.voxel_size_mm", "expected at most 4096 voxels along an axis, found " +
                                          format_number(count) + " along axis " + std::to_string(a));
        return;
      }
      total *= static_cast<std::int64_t>(count);
    }
    if (total > (std::int64_t{1} << 31)) {
      problem("grid.voxel_size_mm", "expected at most 2^31 voxels, found " + std::to_string(total));
      return;
    }
    // The tessellation grows about 4x per halving of its tolerance: a hundredth of the smallest
    // voxel edge (or 0.01 mm, when the voxels are coarser than 1 mm: the meshes written beside
    // coarse images may still be fine) is far below what a voxel shows, and bounds the triangle
    // count (a tolerance of 1e-9 mm would ask for more triangles than memory holds and never end).
    const double finest = std::min(g.voxel_size_mm.minCoeff() / 100.0, 0.01);
    if (m_scene.voxelization.tessellation_tolerance_mm < finest) {
      problem("voxelization.tessellation_tolerance_mm",
              "expected at least a hundredth of the smallest voxel edge or 0.01 mm, whichever is smaller (" +
                  format_number(finest) + " mm), found " +
                  format_number(m_scene.voxelization.tessellation_tolerance_mm) + " mm");
    }
  }

  bool tissue_known(const std::string& tissue) const {
    if (TissueTable::builtin().has_tissue(tissue)) return true;
    for (const auto& t : m_scene.mri.tissues) {
      if (t.tissue == tissue) return true;
    }
    return false;
  }

  void check_organs() {
    const auto& organs = m_scene.anatomy.organs;
    std::set<std::string> names;
    bool unique_names = true;
    for (std::size_t i = 0; i < organs.size(); ++i) {
      const OrganSettings& organ = organs[i];
      if (!names.insert(organ.name).second) {
        unique_names = false;
        problem(indexed("anatomy.organs", i, "name"),
                "expected a unique organ name, found '" + organ.name + "' a second time");
      }
      if (!tissue_known(organ.tissue)) {
        problem(indexed("anatomy.organs", i, "tissue"),
                "expected a tissue of the built-in table or of the scene's tissues section, found '" +
                    organ.tissue + "'");
      }
      if (!shape_source(organ.shape.kind).has_interior && organ.solid) {
        problem(indexed("anatomy.organs", i, "shape.type"),
                std::string("a ") + to_string(organ.shape.kind) +
                    " has no interior: expected 'solid: false' on this organ, found solid (the default)");
      }
      if (!organ.material.empty() && m_scene.deformation.find_material(organ.material) == nullptr) {
        problem(indexed("anatomy.organs", i, "material"),
                "expected a material defined under materials, found '" + organ.material + "'");
      }
      // With duplicate names a reference is ambiguous: report the duplicate alone.
      if (!organ.inside.empty() && unique_names) {
        if (organ.inside == organ.name) {
          problem(indexed("anatomy.organs", i, "inside"), "expected another organ, found the organ itself");
        } else if (m_scene.find_organ(organ.inside) == nullptr) {
          problem(indexed("anatomy.organs", i, "inside"),
                  "expected the name of an organ in this scene, found '" + organ.inside + "'");
        }
      }
    }
    if (!unique_names) return;
    // Nesting must be a forest: following 'inside' from any organ reaches an outermost organ.
    for (std::size_t i = 0; i < organs.size(); ++i) {
      std::set<std::string> chain{organs[i].name};
      const OrganSettings* current = &organs[i];
      while (current != nullptr && !current->inside.empty()) {
        if (!chain.insert(current->inside).second) {
          problem(indexed("anatomy.organs", i, "inside"),
                  "expected nesting without cycles, found a cycle through '" + current->inside + "'");
          return;
        }
        current = m_scene.find_organ(current->inside);
      }
    }
    check_nested_sizes();
  }

  /// An organ cannot fit in a container smaller than itself along an axis. Analytic shapes are
  /// checked here by their bounds; those read from files once built (pipeline/anatomy_checks.hpp).
  void check_nested_sizes() {
    const auto& organs = m_scene.anatomy.organs;
    for (std::size_t i = 0; i < organs.size(); ++i) {
      if (organs[i].inside.empty()) continue;
      const OrganSettings* container = m_scene.find_organ(organs[i].inside);
      if (container == nullptr) continue;
      // Only shapes whose bounds are their extent (those of a superquadric may be larger).
      if (shape_source(organs[i].shape.kind).nesting != NestingCheck::by_bounds) continue;
      const std::optional<WorldBox> own = analytic_shape_bounds(organs[i].shape);
      const std::optional<WorldBox> outer = analytic_shape_bounds(container->shape);
      if (!own || !outer) continue;
      const Eigen::Vector3d size = own->max_mm - own->min_mm, room = outer->max_mm - outer->min_mm;
      for (int a = 0; a < 3; ++a) {
        if (size[a] > room[a] * (1.0 + 1e-9)) {
          problem(indexed("anatomy.organs", i, "inside"),
                  "expected a container at least as large as the organ it holds, found '" + container->name +
                      "' " + format_number(room[a]) + " mm across along " + "xyz"[a] + " and '" +
                      organs[i].name + "' " + format_number(size[a]) + " mm");
          break;
        }
      }
    }
  }

  void check_organ_reference(const std::string& key_path, const std::string& organ) {
    if (m_scene.find_organ(organ) == nullptr) {
      problem(key_path, "expected the name of an organ in this scene, found '" + organ + "'");
    }
  }

  /// A load's organs (they exist; the one it acts on is not fixed) and its member's own checks.
  void check_load(const DeformationSettings& d, std::size_t i, const std::vector<LoadOrgan>& organs) {
    const LoadSettings& load = d.loads[i];
    const LoadType& type = load_type(load.kind);
    for (const LoadParameter& p : type.parameters) {
      if (p.kind != LoadParameter::Kind::organs) continue;
      const std::vector<std::string>& names = load.*p.names;
      for (std::size_t j = 0; j < names.size(); ++j)
        check_organ_reference(indexed("deformation.loads", i, p.key) + "[" + std::to_string(j) + "]",
                              names[j]);
    }
    if (type.check != nullptr)
      for (const LoadProblem& found : type.check(d, i, organs))
        problem(indexed("deformation.loads", i, found.key), found.message);
    for (const LoadParameter& p : type.parameters) {
      if (p.kind != LoadParameter::Kind::organ || (p.recorded != nullptr && !p.recorded(load))) continue;
      const std::string& organ = load.*p.text;
      check_organ_reference(indexed("deformation.loads", i, p.key), organ);
      for (const std::string& fixed : d.fixed)
        if (fixed == organ)
          problem(indexed("deformation.loads", i, p.key), "expected an organ that is not fixed, found '" +
                                                              organ + "', listed under deformation.fixed");
    }
  }

  void check_deformation() {
    const DeformationSettings& d = m_scene.deformation;
    for (std::size_t i = 0; i < d.fixed.size(); ++i) {
      check_organ_reference(indexed("deformation.fixed", i, ""), d.fixed[i]);
    }
    std::vector<LoadOrgan> load_organs;
    for (const OrganSettings& organ : m_scene.anatomy.organs)
      load_organs.push_back({organ.name, organ.solid});
    for (std::size_t i = 0; i < d.loads.size(); ++i)
      check_load(d, i, load_organs);
    if (d.mode == DeformationMode::none && !d.loads.empty()) {
      problem("deformation.mode", "expected quasi_static or dynamic when loads are given, found 'none'");
    }
    for (std::size_t i = 0; i < d.collisions.size(); ++i) {
      const auto& organs = d.collisions[i].organs;
      for (std::size_t j = 0; j < organs.size(); ++j)
        check_organ_reference(indexed("deformation.collisions", i, "organs") + "[" + std::to_string(j) + "]",
                              organs[j]);
      if (organs.size() == 2 && organs[0] == organs[1])
        problem(indexed("deformation.collisions", i, "organs"),
                "expected two different organs, found '" + organs[0] + "' twice");
    }
    const std::string& gap_tissue = m_scene.voxelization.gap_tissue;
    if (!gap_tissue.empty() && gap_tissue != "air") {
      bool used = false;
      for (const auto& organ : m_scene.anatomy.organs)
        used = used || organ.tissue == gap_tissue;
      if (!used) {
        problem("deformation.gap_tissue",
                "expected air or the tissue of an organ of this scene (what fills the space a moved organ "
                "leaves), found '" +
                    gap_tissue + "'");
      }
    }
    if (d.mode == DeformationMode::none && !d.obstacles.empty()) {
      problem("deformation.mode", "expected quasi_static or dynamic when obstacles are given, found 'none'");
    }
    check_stiffness_under_gravity();
    if (solver_type(d.solver.method).steps_in_time && d.mode == DeformationMode::quasi_static) {
      problem("deformation.solver.method", "expected " + static_solver_names() +
                                               " for a quasi_static scene (" + to_string(d.solver.method) +
                                               " steps in time: it needs mode dynamic), found " +
                                               to_string(d.solver.method));
    }
  }

  /// Gravity strains a body of size L by about density g L / E: a material so soft that this is
  /// beyond 10^6 (E = 1e-300 Pa) makes a solve of no physical meaning and numbers past any
  /// float. (A 1 Pa brain under 1 g, strained about 10^3, runs and warns of inverted tets.)
  void check_stiffness_under_gravity() {
    const DeformationSettings& d = m_scene.deformation;
    if (d.mode == DeformationMode::none) return;
    double gravity = 0.0;
    for (const LoadSettings& load : d.loads)
      if (load_type(load.kind).accelerates_masses) gravity = std::max(gravity, load.acceleration_m_s2.norm());
    if (!(gravity > 0.0)) return;
    const double size_m = m_scene.grid.field_of_view_mm.maxCoeff() / 1000.0;
    constexpr double k_largest_strain = 1e6;
    for (const MaterialSettings& material : d.materials) {
      const double strain = material.density_kg_m3 * gravity * size_m / material.youngs_modulus_Pa;
      if (strain > k_largest_strain) {
        problem("materials." + material.name + ".youngs_modulus_Pa",
                "expected a modulus gravity strains by at most 10^6 (density x gravity x field of view / E "
                "<= 10^6, E >= " +
                    format_number(material.density_kg_m3 * gravity * size_m / k_largest_strain) +
                    " Pa under " + format_number(gravity) + " m/s^2), found " +
                    format_number(material.youngs_modulus_Pa) + " Pa: a strain of about " +
                    format_number(strain));
      }
    }
  }

  /// The timing checks of the sequence's member of the registry (mri/sequences/).
  void check_sequence_timing(std::size_t i, const SequenceSettings& s) {
    for (const SequenceProblem& p : sequence_type(s.kind).check(s))
      problem(indexed("sequences", i, p.key), p.message);
  }

  /// The quantities a sequence's signal equation reads (docs/volumes-and-images.md, MR images).
  static std::vector<std::string> needed_values(const SequenceSettings& s) {
    return sequence_type(s.kind).tissue_values(s);
  }

  bool has_value(const std::string& tissue, const std::string& quantity) const {
    for (const auto& t : m_scene.mri.tissues) {
      if (t.tissue != tissue) continue;
      if (quantity == "T1_ms" && t.T1_ms) return true;
      if (quantity == "T2_ms" && t.T2_ms) return true;
      if (quantity == "T2star_ms" && t.T2star_ms) return true;
      if (quantity == "PD" && t.PD) return true;
    }
    const TissueRecord* record = TissueTable::builtin().find(tissue, m_scene.mri.field_strength_T);
    if (record == nullptr) return false;
    if (quantity == "T1_ms") return record->T1_ms.has_value();
    if (quantity == "T2_ms") return record->T2_ms.has_value();
    if (quantity == "T2star_ms") return record->T2star_ms.has_value();
    return record->PD.has_value();
  }

  void check_sequences() {
    std::set<std::string> names;
    std::set<std::string> reported;
    std::vector<std::string> tissues;
    for (const auto& organ : m_scene.anatomy.organs) {
      if (tissue_known(organ.tissue) &&
          std::find(tissues.begin(), tissues.end(), organ.tissue) == tissues.end()) {
        tissues.push_back(organ.tissue);
      }
    }
    for (const TissueRegionSettings& region : m_scene.mri.regions) {
      if (tissue_known(region.tissue) &&
          std::find(tissues.begin(), tissues.end(), region.tissue) == tissues.end()) {
        tissues.push_back(region.tissue);
      }
    }
    for (std::size_t i = 0; i < m_scene.mri.sequences.size(); ++i) {
      const SequenceSettings& s = m_scene.mri.sequences[i];
      if (!names.insert(s.name).second) {
        problem(indexed("sequences", i, "name"),
                "expected a unique sequence name, found '" + s.name + "' again");
      }
      check_sequence_timing(i, s);
      for (const auto& tissue : tissues) {
        for (const auto& quantity : needed_values(s)) {
          if (has_value(tissue, quantity) || !reported.insert(tissue + "." + quantity).second) continue;
          problem(indexed("sequences", i, "type"),
                  "this sequence needs " + quantity + " of tissue '" + tissue + "' at " +
                      format_number(m_scene.mri.field_strength_T) +
                      " T, which the built-in table lacks; expected tissues." + tissue + "." + quantity +
                      " in the scene, found none");
        }
      }
    }
    const AcquisitionSettings& a = m_scene.mri.acquisition;
    if (a.noise_percent > 0.0 && !m_scene.mri.sequences.empty() &&
        std::find(tissues.begin(), tissues.end(), a.noise_reference_tissue) == tissues.end()) {
      problem("acquisition.noise_reference_tissue",
              "expected the tissue of an organ in this scene (noise is relative to its signal), found '" +
                  a.noise_reference_tissue + "'");
    }
    if (a.acquired_voxel_mm) {
      for (int axis = 0; axis < 3; ++axis) {
        const double acquired = (*a.acquired_voxel_mm)[axis], object = m_scene.grid.voxel_size_mm[axis];
        if (acquired < object * (1.0 - 1e-9)) {
          problem("acquisition.acquired_voxel_mm",
                  "expected acquired voxels no smaller than the grid's (" + format_number(object) +
                      " mm along axis " + std::to_string(axis) + "; the grid samples the object), found " +
                      format_number(acquired) + " mm");
          break;
        }
      }
    }
  }

  /// Tissue regions name an organ of an atlas's labels, a tissue and a dseg name of their own;
  /// textured tissues are the phantom's.
  void check_material_maps() {
    std::set<std::string> names;
    for (const auto& organ : m_scene.anatomy.organs)
      names.insert(organ.name);
    names.insert("background");
    names.insert("gap"); // the deformed state's gap label (voxelize/voxelized_phantom.hpp)
    std::vector<std::string> phantom_tissues;
    for (const auto& organ : m_scene.anatomy.organs)
      phantom_tissues.push_back(organ.tissue);
    const auto& regions = m_scene.mri.regions;
    for (std::size_t i = 0; i < regions.size(); ++i) {
      const TissueRegionSettings& region = regions[i];
      const OrganSettings* organ = m_scene.find_organ(region.organ);
      if (!organ) {
        problem(indexed("tissue_regions", i, "organ"),
                "expected the name of an organ in this scene, found '" + region.organ + "'");
      } else if (organ->shape.atlas.empty()) { // only sources of atlas labels name an atlas
        problem(indexed("tissue_regions", i, "organ"),
                "expected an organ whose shape is a label volume of an atlas (the region's labels are "
                "the atlas's), found '" +
                    region.organ + "'");
      }
      if (!tissue_known(region.tissue)) {
        problem(indexed("tissue_regions", i, "tissue"),
                "expected a tissue of the built-in table or of the scene's tissues section, found '" +
                    region.tissue + "'");
      }
      if (!names.insert(region_name(region)).second) {
        const bool named = !region.name.empty();
        problem(indexed("tissue_regions", i, named ? "name" : "label"),
                std::string(named ? "expected a name" : "expected a label (or a name of the region's own)") +
                    " that names no organ and no other region (it names the region's dseg label), found '" +
                    region_name(region) + "' again");
      }
      phantom_tissues.push_back(region.tissue);
    }
    const TextureSettings& texture = m_scene.mri.texture;
    for (std::size_t i = 0; i < texture.tissues.size(); ++i) {
      if (std::find(phantom_tissues.begin(), phantom_tissues.end(), texture.tissues[i]) ==
          phantom_tissues.end())
        problem("texture.tissues[" + std::to_string(i) + "]",
                "expected a tissue of an organ or tissue region in this scene, found '" + texture.tissues[i] +
                    "'");
    }
    const bool reads_scan =
        texture.source == TextureSource::scan ||
        (texture.source == TextureSource::random && texture.spectrum == RandomSpectrum::scan);
    if (texture.spectrum == RandomSpectrum::scan && texture.source != TextureSource::random)
      problem("texture.spectrum", "expected spectrum: scan only with source: random, found source: " +
                                      std::string(to_string(texture.source)));
    if (!reads_scan && !texture.scan.empty())
      problem("texture.scan",
              "expected a scan only with source: scan or spectrum: scan, found one with source: " +
                  std::string(to_string(texture.source)));
    if (!texture.match.empty()) {
      std::string sequences;
      bool found = false;
      for (const SequenceSettings& sequence : m_scene.mri.sequences) {
        sequences += (sequences.empty() ? "" : ", ") + sequence.name;
        found = found || sequence.name == texture.match;
      }
      if (texture.source == TextureSource::none)
        problem("texture.match",
                "expected match only with a texture (source: scan or random), found source: none");
      else if (!found)
        problem("texture.match", "expected the name of one of the scene's sequences (" + sequences +
                                     "), found '" + texture.match + "'");
    }
  }

private:
  YamlContext& m_context;
  const Scene& m_scene;
};

} // namespace

void check_consistency(YamlContext& context, const Scene& scene) {
  ConsistencyChecker checker(context, scene);
  checker.check_grid();
  checker.check_organs();
  checker.check_deformation();
  checker.check_sequences();
  checker.check_material_maps();
}

} // namespace phantasm::scene_detail
