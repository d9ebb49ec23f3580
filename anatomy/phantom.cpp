#include "anatomy/phantom.hpp"

#include "anatomy/shape_build.hpp"
#include "anatomy/shape_source.hpp"
#include "anatomy/smooth_warp.hpp"
#include "core/cancellation.hpp"
#include "core/error.hpp"
#include "core/format.hpp"
#include "core/parallel_tasks.hpp"

#include <Eigen/Geometry>

#include <omp.h>

#include <algorithm>
#include <cstring>
#include <functional>
#include <memory>
#include <mutex>
#include <numeric>
#include <optional>
#include <random>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <type_traits>
#include <vector>

namespace phantasm {
namespace {

/// Seeded size variation: a global scale and anisotropy shared by every organ (an affine map,
/// so nesting is kept exactly) and a small per-organ jitter that is dropped where it would break
/// nesting.
struct Variation {
  Eigen::Vector3d global{1, 1, 1};
  std::vector<Eigen::Vector3d> per_organ;
};

Variation draw_variation(const AnatomySettings& anatomy) {
  Variation variation;
  const double v = anatomy.variation;
  std::mt19937_64 random(anatomy.seed);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const double scale = 1.0 + v * unit(random);
  for (int a = 0; a < 3; ++a)
    variation.global[a] = scale * (1.0 + 0.3 * v * unit(random));
  for (std::size_t o = 0; o < anatomy.organs.size(); ++o) {
    Eigen::Vector3d jitter;
    for (int a = 0; a < 3; ++a)
      jitter[a] = 1.0 + 0.2 * v * unit(random);
    variation.per_organ.push_back(jitter);
  }
  return variation;
}

/// A shape given by its settings alone (no file read): scaled by the seeded variation.
bool analytic(ShapeKind kind) {
  return shape_source(kind).input == ShapeInput::none;
}

ShapeSettings varied(const ShapeSettings& shape, const Eigen::Vector3d& global,
                     const Eigen::Vector3d& jitter) {
  ShapeSettings s = shape;
  // Shapes read from files vary by the shared warp instead (varied_targets).
  if (!analytic(shape.kind)) return s;
  s.center_mm = global.cwiseProduct(shape.center_mm);
  s.radii_mm = global.cwiseProduct(jitter).cwiseProduct(shape.radii_mm);
  s.size_mm = global.cwiseProduct(jitter).cwiseProduct(shape.size_mm);
  return s;
}

/// True when every sampled surface point of `inner` lies inside `outer` by at least margin_mm.
bool contained(const ImplicitShape& inner, const ImplicitShape& outer, double margin_mm) {
  const TriangleMesh directions = unit_icosphere(3);
  for (Eigen::Index v = 0; v < directions.vertex_count(); ++v) {
    const Eigen::Vector3d p = inner.ray_from_center(directions.vertex(v));
    if (outer.value(p) <= 0.0 || (outer.project(p) - p).norm() < margin_mm) return false;
  }
  return true;
}

bool disjoint(const ImplicitShape& a, const ImplicitShape& b) {
  const TriangleMesh directions = unit_icosphere(3);
  for (Eigen::Index v = 0; v < directions.vertex_count(); ++v) {
    if (b.value(a.ray_from_center(directions.vertex(v))) >= 0.0) return false;
    if (a.value(b.ray_from_center(directions.vertex(v))) >= 0.0) return false;
  }
  return true;
}

/// How densely the fit report samples each patch surface (measure_source_fit): about every millimetre,
/// however small the patches.
constexpr double k_fit_sample_spacing_mm = 1.0;

/// The quality bound of solid organs' tet meshes: every tet positive, no dihedral angle below 10
/// degrees, so no tet is near-degenerate.
constexpr double k_min_dihedral_deg = 10.0;

std::uint32_t organ_seed(std::uint64_t scene_seed, std::size_t organ_index) {
  std::seed_seq sequence{static_cast<std::uint32_t>(scene_seed), static_cast<std::uint32_t>(scene_seed >> 32),
                         static_cast<std::uint32_t>(organ_index)};
  std::uint32_t seed = 0;
  sequence.generate(&seed, &seed + 1);
  return seed;
}

int base_triangles(const AnatomySettings& anatomy, std::size_t organ) {
  const int own = anatomy.organs[organ].base_mesh_triangles;
  return own > 0 ? own : anatomy.base_mesh_triangles;
}

/// A closed solid: CGAL tets whose boundary becomes the patch base mesh, vertices placed to
/// straddle the target, bumps fitted.
void build_solid(Organ& organ, const AnatomySettings& anatomy, std::size_t index) {
  const ImplicitShape& target = *organ.target;
  // The surface area of a fine plain mesh of the target sets the facet size for the base size:
  // an icosphere cast from the centre of a star-shaped target, the extracted surface of another.
  const TriangleMesh probe = [&] {
    if (!target.star_shaped()) return surface_base_mesh(target, 5120, organ_seed(anatomy.seed, index));
    TriangleMesh m = unit_icosphere(4);
    for (Eigen::Index v = 0; v < m.vertex_count(); ++v)
      m.vertices.row(v) = target.ray_from_center(m.vertex(v)).transpose();
    return m;
  }();
  const TetMeshCriteria criteria =
      criteria_for_boundary_size(surface_area(probe), base_triangles(anatomy, index));
  // Mesh_3's sliver removal usually clears the quality bound; when it does not, mesh again from
  // another seed (deterministic: the attempts follow the scene seed).
  TetMesh tets;
  // The quality bound is checked after the boundary vertices moved to straddle the target,
  // since that move changes the boundary tets' angles a little.
  TriangleMesh base;
  for (std::uint32_t attempt = 0; attempt < 8; ++attempt) {
    progress_detail(organ.name + ": tet meshing (CGAL Mesh_3" +
                    (attempt > 0 ? ", attempt " + std::to_string(attempt + 1) : std::string()) + ")");
    tets = mesh_implicit_solid(target, criteria, organ_seed(anatomy.seed, index) + attempt);
    base = boundary_surface(tets, &organ.tet_vertex_of_surface_vertex);
    base.vertices = straddle_vertices(base, target, PatchFitOptions{}.vertex_offset_factor);
    for (Eigen::Index v = 0; v < base.vertex_count(); ++v) {
      tets.vertices.row(organ.tet_vertex_of_surface_vertex[v]) = base.vertices.row(v);
    }
    if (min_dihedral_angle_deg(tets) >= k_min_dihedral_deg) break;
  }
  progress_detail(organ.name + ": fitting " + std::to_string(base.face_count()) + " patches");
  PatchSurface surface(base, "organ " + organ.name);
  fit_bumps(surface, target, PatchFitOptions{});
  match_volume(surface, target.volume());
  organ.surface = std::move(surface);
  organ.solid = std::move(tets);
}

} // namespace

const Organ* Phantom::find(const std::string& name) const {
  for (const auto& organ : organs) {
    if (organ.name == name) return &organ;
  }
  return nullptr;
}

std::unique_ptr<ImplicitShape> target_shape(const ShapeSettings& shape, const ShapeData* file,
                                            const std::string& organ) {
  return shape_build(shape.kind).target(shape, file, organ);
}

namespace {

/// A target shape made on its first use. A phantom read from the anatomy cache carries its
/// organs' targets, but most runs that read it never ask them anything (only meshing a body
/// does, and the body mesh cache holds the meshes): a label volume's target smooths the organ's
/// labels over their whole box, seconds of every run of a Colin head for nothing.
/// Thread-safe: the first call from any thread makes it, the others wait for it.
class DeferredShape final : public ImplicitShape {
public:
  explicit DeferredShape(std::function<std::unique_ptr<ImplicitShape>()> make) : m_make(std::move(make)) {}
  double value(const Eigen::Vector3d& x) const override { return shape().value(x); }
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const override { return shape().gradient(x); }
  Eigen::Vector3d center() const override { return shape().center(); }
  double bounding_radius() const override { return shape().bounding_radius(); }
  double volume() const override { return shape().volume(); }
  bool star_shaped() const override { return shape().star_shaped(); }
  bool smoothed_indicator() const override { return shape().smoothed_indicator(); }
  double slope_bound(const Eigen::Vector3d& direction) const override {
    return shape().slope_bound(direction);
  }

private:
  const ImplicitShape& shape() const {
    std::call_once(m_once, [this] { m_shape = m_make(); });
    return *m_shape;
  }
  std::function<std::unique_ptr<ImplicitShape>()> m_make;
  mutable std::once_flag m_once;
  mutable std::unique_ptr<ImplicitShape> m_shape;
};

/// The organs' target shapes with seeded variation (a jitter that would break nesting or touch
/// a sibling is dropped), and the shape settings they were made from.
struct VariedTargets {
  std::vector<ShapeSettings> shapes;
  std::vector<std::shared_ptr<const ImplicitShape>> targets;
};

/// With `deferred`, the targets of shapes read from files are made on their first use
/// (DeferredShape): for a phantom decoded from the cache, whose geometry is already built.
VariedTargets varied_targets(const AnatomySettings& anatomy, const std::map<std::string, ShapeData>& files,
                             Reporter& reporter, bool deferred) {
  const auto& settings = anatomy.organs;
  Variation variation = draw_variation(anatomy);
  // Shapes read from files vary by one smooth warp of space shared by all of them (nesting kept).
  const SmoothWarp warp = draw_shape_warp(files, anatomy.variation, anatomy.seed);
  const std::map<std::string, ShapeData> warped = warped_shapes(files, warp);
  if (!warp.identity()) {
    reporter.modelled(
        "anatomy", "label volumes and meshes warped smoothly by up to " + format_number(warp.amplitude_mm()) +
                       " mm from seed " + std::to_string(anatomy.seed) +
                       " (seeded variation: one warp for all of them, so the organs stay nested)");
  }
  VariedTargets out;
  auto& shapes = out.shapes;
  auto& targets = out.targets;
  const auto file_of = [&](std::size_t o) -> const ShapeData* {
    const auto found = warped.find(settings[o].name);
    return found == warped.end() ? nullptr : &found->second;
  };
  // The targets of shapes read from files (a label volume's smooths the organ's labels over their
  // box, a second or so each on a Colin head) side by side: they take no jitter check below.
  std::vector<std::shared_ptr<const ImplicitShape>> from_files(settings.size());
  if (!deferred) {
    run_tasks_in_parallel(
        settings.size(), static_cast<std::size_t>(std::max(1, omp_get_max_threads())), [&](std::size_t o) {
          const ShapeSettings shape = varied(settings[o].shape, variation.global, variation.per_organ[o]);
          if (file_of(o) != nullptr && !analytic(shape.kind))
            from_files[o] = target_shape(shape, file_of(o), settings[o].name);
        });
  }
  for (std::size_t o = 0; o < settings.size(); ++o) {
    const ShapeData* file = file_of(o);
    ShapeSettings shape = varied(settings[o].shape, variation.global, variation.per_organ[o]);
    if (from_files[o]) {
      shapes.push_back(shape);
      targets.push_back(from_files[o]);
      continue;
    }
    if (deferred && file != nullptr && !analytic(shape.kind)) {
      // Files' shapes vary by the warp alone (no jitter, no nesting checks below).
      targets.push_back(std::make_shared<DeferredShape>(
          [shape, data = *file, name = settings[o].name] { return target_shape(shape, &data, name); }));
      shapes.push_back(shape);
      continue;
    }
    std::shared_ptr<const ImplicitShape> target = target_shape(shape, file, settings[o].name);
    if (target && analytic(shape.kind) && variation.per_organ[o] != Eigen::Vector3d::Ones()) {
      bool keeps_nesting = true;
      for (std::size_t p = 0; p < o; ++p) {
        if (!targets[p] || !analytic(shapes[p].kind)) continue;
        if (settings[o].inside == settings[p].name)
          keeps_nesting = keeps_nesting && contained(*target, *targets[p], 0.5);
        if (settings[p].inside == settings[o].name)
          keeps_nesting = keeps_nesting && contained(*targets[p], *target, 0.5);
        if (!settings[o].inside.empty() && settings[o].inside == settings[p].inside) {
          keeps_nesting = keeps_nesting && disjoint(*target, *targets[p]);
        }
      }
      if (!keeps_nesting) {
        shape = varied(settings[o].shape, variation.global, Eigen::Vector3d::Ones());
        target = target_shape(shape, file, settings[o].name);
        reporter.modelled("anatomy", settings[o].name + ": own size jitter dropped to keep the nesting");
      }
    }
    shapes.push_back(shape);
    targets.push_back(target);
  }
  return out;
}

/// An organ's names and target, before its geometry.
Organ organ_without_geometry(const OrganSettings& s, std::shared_ptr<const ImplicitShape> target) {
  Organ organ;
  organ.name = s.name;
  organ.tissue = s.tissue;
  organ.material = s.material;
  organ.inside = s.inside;
  organ.target = std::move(target);
  return organ;
}

/// Builds one organ's geometry: its source's own (a sheet, a structured box), or a fitted solid
/// or surface.
void build_organ_geometry(Organ& organ, const AnatomySettings& anatomy, std::size_t o,
                          const ShapeSettings& shape, ProgressBar& progress) {
  const OrganSettings& s = anatomy.organs[o];
  const ShapeBuild& build = shape_build(shape.kind);
  if (build.geometry != nullptr) {
    build.geometry(organ, s, shape);
  } else if (s.solid) {
    build_solid(organ, anatomy, o);
    progress.set_detail(s.name + ": measuring the fit");
    organ.fit = measure_source_fit(*organ.surface, *organ.target,
                                   surface_sample_level_for_spacing(*organ.surface, k_fit_sample_spacing_mm));
  } else {
    PatchFitOptions options;
    options.base_triangles = base_triangles(anatomy, o);
    progress.set_detail(s.name + ": fitting about " + std::to_string(options.base_triangles) + " patches");
    const Eigen::Vector3d hint = build.fit_hint ? build.fit_hint(shape) : Eigen::Vector3d::Ones();
    organ.surface.emplace(fit_patch_surface(*organ.target, hint, rotation_from_degrees(shape.rotation_deg),
                                            options, "organ " + s.name));
    progress.set_detail(s.name + ": measuring the fit");
    organ.fit = measure_source_fit(*organ.surface, *organ.target,
                                   surface_sample_level_for_spacing(*organ.surface, k_fit_sample_spacing_mm));
  }
  // The patches' height bounds, which every level set of the organ needs, once with the anatomy
  // (and stored with it: encode_organ_geometry).
  if (organ.surface) organ.surface->hold_height_ranges();
}

/// The log line of a built organ.
std::string organ_line(const Organ& organ) {
  std::ostringstream line;
  line << organ.name << ": ";
  if (organ.sheet) {
    line << "sheet of " << organ.sheet->face_count() << " triangles (zero thickness: no volume to voxelize)";
  }
  if (organ.surface) {
    line << organ.surface->patch_count() << " patches";
    if (organ.solid) {
      line << ", " << organ.solid->vertices.rows() << " vertices / " << organ.solid->tets.rows()
           << " tets (min dihedral " << format_number(min_dihedral_angle_deg(*organ.solid)) << " deg)";
    }
    line << ", volume " << format_number(organ.surface->volume() / 1000.0)
         << " ml, fit to the source boundary: mean " << format_number(organ.fit.source_mean_mm) << ", p95 "
         << format_number(organ.fit.source_p95_mm) << ", max " << format_number(organ.fit.source_max_mm)
         << " mm, volume error " << format_number(100.0 * organ.fit.volume_error) << " %";
  }
  return line.str();
}

// The geometry encoding (encode_organ_geometry): native-endian raw values, each array preceded by
// its dimensions. Bumped whenever the layout or what an organ holds changes.
constexpr std::uint32_t k_geometry_format = 5;

} // namespace

Phantom build_phantom(const AnatomySettings& anatomy, const std::map<std::string, ShapeData>& files,
                      Reporter& reporter) {
  const auto& settings = anatomy.organs;
  const VariedTargets varied = varied_targets(anatomy, files, reporter, false);
  Phantom phantom;
  phantom.tet_size_mm = anatomy.tet_size_mm;
  phantom.tet_facet_distance_mm = anatomy.tet_facet_distance_mm;
  phantom.tet_interfaces = anatomy.tet_interfaces;
  phantom.seed = anatomy.seed;
  ProgressBar progress(reporter, "anatomy", settings.size());
  // Organs are fitted side by side, one per thread (each fit is the same on any thread: its
  // own parallel loops write their own slots, and each mesher reseeds its thread's generator),
  // and logged in scene order. The largest base meshes are taken first, so the small organs fill
  // the threads at the end instead of one large fit running alone (on the Colin head grey and
  // white matter, 40 000 triangles each, come fourth and fifth in scene order).
  std::vector<std::size_t> order(settings.size());
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return base_triangles(anatomy, a) > base_triangles(anatomy, b);
  });
  std::vector<std::optional<Organ>> built(settings.size());
  run_tasks_in_parallel(settings.size(), static_cast<std::size_t>(std::max(1, omp_get_max_threads())),
                        [&](std::size_t task) {
                          const std::size_t o = order[task];
                          throw_if_cancelled();
                          Organ organ = organ_without_geometry(settings[o], varied.targets[o]);
                          build_organ_geometry(organ, anatomy, o, varied.shapes[o], progress);
                          built[o] = std::move(organ);
                          progress.advance();
                        });
  for (std::optional<Organ>& organ : built) {
    reporter.modelled("anatomy", organ_line(*organ));
    phantom.organs.push_back(std::move(*organ));
  }
  return phantom;
}

std::string encode_organ_geometry(const Phantom& phantom) {
  ByteWriter out;
  out.value(k_geometry_format);
  out.value(static_cast<std::uint64_t>(phantom.organs.size()));
  for (const Organ& organ : phantom.organs) {
    out.text(organ.name);
    out.value(static_cast<std::uint8_t>(organ.surface.has_value()));
    if (organ.surface) {
      const PatchSurface& surface = *organ.surface;
      if (surface.base_mesh().vertices != surface.rest_positions())
        throw std::logic_error("encode_organ_geometry: organ " + organ.name + " is not at rest");
      out.matrix(surface.rest_positions());
      out.matrix(surface.base_mesh().faces);
      for (Eigen::Index t = 0; t < surface.patch_count(); ++t) {
        const std::vector<PatchBump>& bumps = surface.bumps(t);
        out.value(static_cast<std::uint32_t>(bumps.size()));
        for (const PatchBump& bump : bumps) {
          // Seven doubles: c (2), S (4, column-major), amplitude.
          for (int i = 0; i < 2; ++i)
            out.value(bump.center_uv[i]);
          for (int i = 0; i < 4; ++i)
            out.value(bump.shape_uv.data()[i]);
          out.value(bump.amplitude_mm);
        }
      }
      // Each patch's height bounds, lowest and highest (computed here when not held).
      const std::vector<HeightRange> computed =
          surface.height_ranges() ? std::vector<HeightRange>() : patch_height_ranges(surface);
      for (const HeightRange& range : surface.height_ranges() ? *surface.height_ranges() : computed) {
        out.value(range.lowest);
        out.value(range.highest);
      }
    }
    out.value(static_cast<std::uint8_t>(organ.sheet.has_value()));
    if (organ.sheet) {
      out.matrix(organ.sheet->vertices);
      out.matrix(organ.sheet->faces);
    }
    out.value(static_cast<std::uint8_t>(organ.solid.has_value()));
    if (organ.solid) {
      out.matrix(organ.solid->vertices);
      out.matrix(organ.solid->tets);
      out.matrix(organ.solid->boundary_faces);
      out.matrix(organ.solid->subdomains);
    }
    out.matrix(organ.tet_vertex_of_surface_vertex);
    // Field by field: the struct's padding bytes are undefined.
    out.value(organ.fit.base_triangles);
    out.value(organ.fit.vertex_offset_factor);
    out.value(organ.fit.volume_error);
    out.value(organ.fit.source_mean_mm);
    out.value(organ.fit.source_p95_mm);
    out.value(organ.fit.source_max_mm);
  }
  return out.take();
}

Phantom phantom_from_geometry(const AnatomySettings& anatomy, const std::map<std::string, ShapeData>& files,
                              std::string_view bytes, Reporter& reporter) {
  const auto& settings = anatomy.organs;
  ByteReader in(bytes, "organ geometry");
  if (in.value<std::uint32_t>() != k_geometry_format)
    throw DamagedGeometry("organ geometry: written in another format");
  if (in.value<std::uint64_t>() != settings.size())
    throw DamagedGeometry("organ geometry: another number of organs");
  // Decoded before the targets are made, so that damaged bytes cost no shape building.
  std::vector<Organ> organs(settings.size());
  for (std::size_t o = 0; o < settings.size(); ++o) {
    Organ& organ = organs[o];
    organ.name = in.text();
    if (organ.name != settings[o].name)
      throw DamagedGeometry("organ geometry: organ " + organ.name + " where " + settings[o].name +
                            " was expected");
    if (in.value<std::uint8_t>()) {
      TriangleMesh base;
      in.matrix(base.vertices);
      in.matrix(base.faces);
      PatchSurface surface(std::move(base), "organ " + organ.name);
      std::vector<std::vector<PatchBump>> patches(static_cast<std::size_t>(surface.patch_count()));
      for (std::vector<PatchBump>& bumps : patches) {
        bumps.resize(in.value<std::uint32_t>());
        for (PatchBump& bump : bumps) {
          for (int i = 0; i < 2; ++i)
            bump.center_uv[i] = in.value<double>();
          for (int i = 0; i < 4; ++i)
            bump.shape_uv.data()[i] = in.value<double>();
          bump.amplitude_mm = in.value<double>();
        }
      }
      surface.set_all_bumps(std::move(patches));
      std::vector<HeightRange> ranges(static_cast<std::size_t>(surface.patch_count()));
      for (HeightRange& range : ranges) {
        range.lowest = in.value<double>();
        range.highest = in.value<double>();
      }
      try {
        surface.set_height_ranges(std::move(ranges));
      } catch (const InputError& error) {
        throw DamagedGeometry(std::string("organ geometry: ") + error.what());
      }
      organ.surface = std::move(surface);
    }
    if (in.value<std::uint8_t>()) {
      organ.sheet.emplace();
      in.matrix(organ.sheet->vertices);
      in.matrix(organ.sheet->faces);
    }
    if (in.value<std::uint8_t>()) {
      organ.solid.emplace();
      in.matrix(organ.solid->vertices);
      in.matrix(organ.solid->tets);
      in.matrix(organ.solid->boundary_faces);
      in.matrix(organ.solid->subdomains);
    }
    in.matrix(organ.tet_vertex_of_surface_vertex);
    organ.fit.base_triangles = in.value<int>();
    organ.fit.vertex_offset_factor = in.value<double>();
    organ.fit.volume_error = in.value<double>();
    organ.fit.source_mean_mm = in.value<double>();
    organ.fit.source_p95_mm = in.value<double>();
    organ.fit.source_max_mm = in.value<double>();
  }
  if (!in.done()) throw DamagedGeometry("organ geometry: bytes after the last organ");

  const VariedTargets varied = varied_targets(anatomy, files, reporter, true);
  Phantom phantom;
  phantom.tet_size_mm = anatomy.tet_size_mm;
  phantom.tet_facet_distance_mm = anatomy.tet_facet_distance_mm;
  phantom.tet_interfaces = anatomy.tet_interfaces;
  phantom.seed = anatomy.seed;
  for (std::size_t o = 0; o < settings.size(); ++o) {
    Organ organ = organ_without_geometry(settings[o], varied.targets[o]);
    organ.surface = std::move(organs[o].surface);
    organ.sheet = std::move(organs[o].sheet);
    organ.solid = std::move(organs[o].solid);
    organ.tet_vertex_of_surface_vertex = std::move(organs[o].tet_vertex_of_surface_vertex);
    organ.fit = organs[o].fit;
    reporter.modelled("anatomy", organ_line(organ));
    phantom.organs.push_back(std::move(organ));
  }
  return phantom;
}

} // namespace phantasm
