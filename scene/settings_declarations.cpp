#include "scene/settings_declarations.hpp"

#include "anatomy/shape_source.hpp"
#include "mri/sequence_type.hpp"
#include "sim/load_type.hpp"
#include "sim/solver_type.hpp"

#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

namespace phantasm {

/// An organ's bounds as its corners.
template <>
struct SettingValue<WorldBox> {
  static std::string exact(const WorldBox& b) { return exact_text(b.min_mm) + " " + exact_text(b.max_mm); }
  static std::string shown(const WorldBox& b) {
    return format_vector(b.min_mm) + " to " + format_vector(b.max_mm);
  }
  static std::string type() { return "box"; }
  static std::string json(const WorldBox& b) {
    return "[" + SettingValue<Eigen::Vector3d>::json(b.min_mm) + "," +
           SettingValue<Eigen::Vector3d>::json(b.max_mm) + "]";
  }
  static void change(WorldBox& b) { b.max_mm.x() += 1.0; }
  static WorldBox some() { return WorldBox{Eigen::Vector3d::Zero(), Eigen::Vector3d::Ones()}; }
};

/// The atlas of growth regions a run reads (set by the pipeline, not a scene key) by its name.
template <>
struct SettingValue<std::shared_ptr<const RegionAtlas>> {
  using V = std::shared_ptr<const RegionAtlas>;
  static std::string exact(const V& v) { return v ? SettingValue<std::string>::exact(v->name) : "none"; }
  static std::string shown(const V& v) { return v ? v->name + " (" + v->source + ")" : "(none)"; }
  static std::string type() { return "atlas"; }
  static std::string json(const V& v) { return v ? json_string(v->name) : "null"; }
  static void change(V& v) {
    if (v) {
      v.reset();
    } else {
      auto atlas = std::make_shared<RegionAtlas>();
      atlas->name = "aal";
      v = std::move(atlas);
    }
  }
};

namespace {

/// Numbers in [min, max] (the unit is the field's).
NumberRule range(double min, double max) {
  return between(min, max, "");
}

/// Numbers in (min, max].
NumberRule above(double min, double max = std::numeric_limits<double>::infinity()) {
  NumberRule rule = between(min, max, "");
  rule.min_exclusive = true;
  return rule;
}

const NumberRule k_coordinate = range(-1e5, 1e5); ///< a position in mm: within 100 m of the origin
const NumberRule k_positive = above(0.0);
const NumberRule k_triangles = range(20, 200000);

/// Numbers in [0, 0.5) (a Poisson ratio).
NumberRule below_half() {
  NumberRule rule = range(0.0, 0.5);
  rule.max_exclusive = true;
  return rule;
}

/// The accepted values of a registry's parameter.
template <typename Parameter>
NumberRule rule_of(const Parameter& p) {
  return NumberRule{p.min, p.max, p.min_exclusive, p.max_exclusive, p.unit};
}

/// The rule of the first parameter of a registry's members for which `reads` holds: the registry
/// holds the bounds its members' keys are parsed with.
template <typename Member, typename Reads>
NumberRule registry_rule(const std::vector<const Member*>& members, Reads&& reads) {
  for (const Member* member : members)
    for (const auto& p : member->parameters)
      if (reads(p)) return rule_of(p);
  throw std::logic_error("a declared setting that no member of its registry reads");
}

/// The bounds of a shape's number or vector, from the shape source registry (anatomy/shape_source.hpp).
NumberRule shape_rule(double ShapeSettings::*m) {
  return registry_rule(shape_sources(), [m](const ShapeParameter& p) {
    return p.kind == ShapeParameter::Kind::number && p.number == m;
  });
}
NumberRule shape_rule(Eigen::Vector3d ShapeSettings::*m) {
  return registry_rule(shape_sources(), [m](const ShapeParameter& p) {
    return p.kind != ShapeParameter::Kind::number && p.vector == m;
  });
}

/// The bounds of a sequence's number or integer, from the sequence registry (mri/sequence_type.hpp).
NumberRule sequence_rule(double SequenceSettings::*m) {
  return registry_rule(sequence_types(), [m](const SequenceParameter& p) {
    return p.kind == SequenceParameter::Kind::number && p.number == m;
  });
}
NumberRule sequence_rule(int SequenceSettings::*m) {
  return registry_rule(sequence_types(), [m](const SequenceParameter& p) {
    return p.kind == SequenceParameter::Kind::integer && p.integer == m;
  });
}

/// The members of a registry (sequence types, shape sources, solvers, load types) by name, each
/// with its value of `kind`.
template <typename Member, typename Kind>
std::vector<std::pair<std::string, Kind>> by_name(const std::vector<const Member*>& members,
                                                  Kind Member::*kind) {
  std::vector<std::pair<std::string, Kind>> kinds;
  for (const Member* member : members)
    kinds.emplace_back(member->name, member->*kind);
  return kinds;
}

/// The members of a registry whose value is `kind`, by name.
template <typename Member>
auto kinds_by_name(const std::vector<const Member*>& members) {
  return by_name(members, &Member::kind);
}

/// How a load or an obstacle moves in a dynamic scene, by the scene's names.
std::vector<std::pair<std::string, MotionProfile>> motion_profiles() {
  return {
      {"constant", MotionProfile::constant}, {"ramp", MotionProfile::ramp}, {"sine", MotionProfile::sine}};
}

/// Whether a load parameter reads the member.
bool reads(const LoadParameter& p, double LoadSettings::*m) {
  return p.kind == LoadParameter::Kind::number && p.number == m;
}
bool reads(const LoadParameter& p, Eigen::Vector3d LoadSettings::*m) {
  return p.kind == LoadParameter::Kind::vector3 && p.vector == m;
}
bool reads(const LoadParameter& p, std::string LoadSettings::*m) {
  return (p.kind == LoadParameter::Kind::organ || p.kind == LoadParameter::Kind::choice) && p.text == m;
}
bool reads(const LoadParameter& p, std::vector<std::string> LoadSettings::*m) {
  return (p.kind == LoadParameter::Kind::organs || p.kind == LoadParameter::Kind::name_or_names) &&
         p.names == m;
}

/// A load parameter's accepted values as text when it is no number ("aal", "organs of the scene").
std::string bounds_of(const LoadParameter& p) {
  std::string text;
  for (const std::string& choice : p.choices)
    text += (text.empty() ? "" : ", ") + choice;
  if (p.kind == LoadParameter::Kind::organ) text = "an organ that is not fixed";
  if (p.kind == LoadParameter::Kind::organs) text = "organs of the scene";
  return text;
}

/// The names of the load types that read a parameter for which `matches` holds ("gravity,
/// displacement"), and the first such parameter.
template <typename Matches>
std::pair<std::string, const LoadParameter*> load_types_reading(Matches&& matches) {
  std::string names;
  const LoadParameter* first = nullptr;
  for (const LoadType* type : load_types()) {
    for (const LoadParameter& p : type->parameters) {
      if (!matches(p)) continue;
      names += (names.empty() ? "" : ", ") + std::string(type->name);
      if (first == nullptr) first = &p;
      break;
    }
  }
  return {names, first};
}

/// A member of LoadSettings as the load type registry (sim/load_type.hpp) declares it: its scene
/// key, unit and bounds from the first type that reads it, its help after the types that do.
template <typename T>
void load_field(SettingsDeclaration<LoadSettings>& d, T LoadSettings::*member, const std::string& help) {
  const auto [types, p] = load_types_reading([member](const LoadParameter& q) { return reads(q, member); });
  if (p == nullptr) throw std::logic_error("a member of LoadSettings that no load type reads: " + help);
  if (p->kind == LoadParameter::Kind::number || p->kind == LoadParameter::Kind::vector3) {
    d.field(p->key, member, p->unit, rule_of(*p), types + ": " + help);
    if (p->unit_vector) d.bounds_note("not zero");
  } else {
    d.field(p->key, member, p->unit, bounds_of(*p), types + ": " + help);
  }
}

/// Whether a field is the list `name` or a field of its elements.
template <typename S>
bool in_list(const SettingField<S>& f, const std::string& name) {
  return f.name == name || f.name.rfind(name + "[].", 0) == 0;
}

} // namespace

template <>
const std::vector<SettingField<GridSettings>>& declared_settings<GridSettings>() {
  static const auto fields = [] {
    SettingsDeclaration<GridSettings> d;
    // The reference state's key holds the image grid these make (GridSettings::grid()).
    d.shaping(cached_reference_state)
        .field("field_of_view_mm", &GridSettings::field_of_view_mm, "mm", k_positive,
               "extent of the image grid along i, j, k")
        .required()
        .scalar_allowed()
        .field("voxel_size_mm", &GridSettings::voxel_size_mm, "mm", k_positive, "voxel size along i, j, k")
        .required()
        .scalar_allowed()
        .field("center_mm", &GridSettings::center_mm, "mm", k_coordinate, "RAS position of the grid's centre")
        .custom<std::string>(
            "orientation", &GridSettings::orientation, "axis code", "",
            "the grid's axes as a 3-letter code with one of R/L, A/P, S/I each (RAS, LPS, ...)",
            SettingValue<std::string>::exact, SettingValue<std::string>::shown,
            [](std::string& code) { code = code == "RAS" ? "LPS" : "RAS"; });
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<ShapeSettings>>& declared_settings<ShapeSettings>() {
  static const auto fields = [] {
    SettingsDeclaration<ShapeSettings> d;
    d.shaping(cached_anatomy)
        .choice("type", &ShapeSettings::kind, kinds_by_name(shape_sources()),
                "the shape's source: an analytic shape, a mesh file or a label volume")
        .field("center_mm", &ShapeSettings::center_mm, "mm", shape_rule(&ShapeSettings::center_mm),
               "centre of an analytic shape, RAS")
        .field("radii_mm", &ShapeSettings::radii_mm, "mm", shape_rule(&ShapeSettings::radii_mm),
               "semi-axes of an ellipsoid or superquadric before rotation")
        .field("rotation_deg", &ShapeSettings::rotation_deg, "degrees",
               shape_rule(&ShapeSettings::rotation_deg), "rotations about x, then y, then z")
        .field("exponent_1", &ShapeSettings::exponent_1, "", shape_rule(&ShapeSettings::exponent_1),
               "superquadric north-south exponent (1: ellipsoid)")
        .field("exponent_2", &ShapeSettings::exponent_2, "", shape_rule(&ShapeSettings::exponent_2),
               "superquadric east-west exponent (1: ellipsoid)")
        .field("size_mm", &ShapeSettings::size_mm, "mm", shape_rule(&ShapeSettings::size_mm),
               "box edge lengths; sheet: x and y extent")
        .field("cells", &ShapeSettings::cells, "", range(1, 1000),
               "box: hexahedral cells per axis (5 tets each); sheet: x, y")
        .field("file", &ShapeSettings::file, "", "", "mesh or label volume, relative to the scene's folder")
        .field("atlas", &ShapeSettings::atlas, "", "colin27", "label volume made from installed data")
        .field("label", &ShapeSettings::label, "", range(1, 65535),
               "label volume: the first label given by number")
        .field("labels", &ShapeSettings::labels, "", "", "label volume: every label, by number or name")
        .field("smoothing_mm", &ShapeSettings::smoothing_mm, "mm", shape_rule(&ShapeSettings::smoothing_mm),
               "label volume: Gaussian smoothing of the labels' indicator (0: none)");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<OrganSettings>>& declared_settings<OrganSettings>() {
  static const auto fields = [] {
    SettingsDeclaration<OrganSettings> d;
    d.shaping(cached_anatomy)
        .field("name", &OrganSettings::name, "", "a safe name", "the organ's name")
        .required()
        .field("tissue", &OrganSettings::tissue, "", "a safe name", "its tissue")
        .required()
        .field("material", &OrganSettings::material, "", "", "a material of the scene's materials")
        .field("inside", &OrganSettings::inside, "", "", "the organ containing it; empty for the outermost")
        .field("solid", &OrganSettings::solid, "", "", "tetrahedralized interior, or a surface only")
        .field("base_mesh_triangles", &OrganSettings::base_mesh_triangles, "", k_triangles,
               "this organ's patch base mesh size (0: anatomy.base_mesh_triangles)")
        .nested("shape", &OrganSettings::shape, declared_settings<ShapeSettings>())
        .field("thickness_mm", &OrganSettings::thickness_mm, "mm", above(0.0, 1000.0),
               "wall thickness of a surface organ simulated as a shell")
        .field("enclosed_volume_tolerance", &OrganSettings::enclosed_volume_tolerance, "", range(0.0, 0.5),
               "a closed shell's enclosed volume kept within this fraction of rest (unset: free)");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<AnatomySettings>>& declared_settings<AnatomySettings>() {
  static const auto fields = [] {
    SettingsDeclaration<AnatomySettings> d;
    d.shaping(cached_anatomy)
        .field("variation", &AnatomySettings::variation, "relative size", range(0.0, 0.3),
               "seeded relative variation of organ sizes (0: exact)")
        .field("base_mesh_triangles", &AnatomySettings::base_mesh_triangles, "", k_triangles,
               "patch base mesh size per organ (the anatomy's accuracy knob)")
        .field("tet_size_mm", &AnatomySettings::tet_size_mm, "mm", range(0.5, 500.0),
               "element size of one conforming tet mesh per simulated body (0: each organ's own mesh)")
        .field("tet_facet_distance_mm", &AnatomySettings::tet_facet_distance_mm, "mm", range(0.05, 100.0),
               "bound of those meshes' interface distance to the surfaces (0: a tenth of tet_size_mm)")
        .choice("tet_interfaces", &AnatomySettings::tet_interfaces,
                {{"organs", TetInterfaces::organs}, {"materials", TetInterfaces::materials}},
                "which nested surfaces the conforming tet mesh follows")
        .list("organs", &AnatomySettings::organs, "the organs, outermost first",
              declared_settings<OrganSettings>())
        .field("seed", &AnatomySettings::seed, "", "", "seed of the size variation and tet meshing")
        .derived_from("seed");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<VoxelizationSettings>>& declared_settings<VoxelizationSettings>() {
  static const auto fields = [] {
    using V = VoxelizationSettings;
    SettingsDeclaration<V> d;
    d.shaping(cached_reference_state)
        .field("supersampling", &V::supersampling, "", range(1, 16),
               "samples per voxel edge of the partial-volume fractions")
        .field("tessellation_tolerance_mm", &V::tessellation_tolerance_mm, "mm", above(0.0, 10.0),
               "patch surface tessellation deviation")
        .shaping(no_cached_result)
        .field("gap_tissue", &V::gap_tissue, "", "air or an organ's tissue",
               "what fills the space a moved organ leaves (empty: the default)")
        .key_elsewhere("deformation.gap_tissue")
        .shaping(cached_reference_state)
        .field("level_sets_from_tessellation", &V::level_sets_from_tessellation, "", "",
               "level sets through tessellations (benchmarks only; not a scene key)")
        .not_in_scene_file()
        .shaping(no_cached_result)
        .field("deformed", &V::deformed, "", "", "a deformed state is made")
        .derived_from("deformation.mode")
        .field("keep_level_sets", &V::keep_level_sets, "", "", "level sets kept for .vdb files")
        .derived_from("outputs.vdb")
        .field("labels", &V::labels, "", "", "label volumes are made")
        .derived_from("outputs.labels")
        .field("fractions", &V::fractions, "", "", "fraction volumes are made")
        .derived_from("outputs.fractions and outputs.images")
        .field("displacement_fields", &V::displacement_fields, "", "", "displacement fields are made")
        .derived_from("outputs.displacement_fields")
        .field("jacobian", &V::jacobian, "", "", "Jacobian determinants are made")
        .derived_from("outputs.jacobian")
        .field("landmarks", &V::landmarks, "", "", "landmarks are made")
        .derived_from("outputs.landmarks")
        .field("dense_landmarks", &V::dense_landmarks, "", "", "dense landmarks per organ")
        .derived_from("outputs.dense_landmarks and outputs.landmarks")
        .field("gap_fill", &V::gap_fill, "", "", "the tissue of every gap")
        .derived_from("deformation.gap_tissue or the organs")
        .shaping(cached_reference_state)
        .field("organ_bounds_mm", &V::organ_bounds_mm, "mm", "",
               "per organ, the bounds of its shape as written (none: known from its file only)")
        .derived_from("anatomy.organs");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<TissueOverride>>& declared_settings<TissueOverride>() {
  static const auto fields = [] {
    SettingsDeclaration<TissueOverride> d;
    d.shaping(cached_reference_images)
        .field("tissue", &TissueOverride::tissue, "", "", "the tissue whose values it replaces or completes")
        .field("T1_ms", &TissueOverride::T1_ms, "ms", k_positive, "T1 at the scene's field strength")
        .field("T2_ms", &TissueOverride::T2_ms, "ms", k_positive, "T2")
        .field("T2star_ms", &TissueOverride::T2star_ms, "ms", k_positive, "T2*")
        .field("PD", &TissueOverride::PD, "units of CSF proton density", range(0.0, 1.5), "proton density");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<SequenceSettings>>& declared_settings<SequenceSettings>() {
  static const auto fields = [] {
    SettingsDeclaration<SequenceSettings> d;
    d.shaping(cached_reference_images)
        .field("name", &SequenceSettings::name, "", "a BIDS suffix",
               "the image's BIDS suffix (T1w, T2w, ...)")
        .required()
        .choice("type", &SequenceSettings::kind, kinds_by_name(sequence_types()),
                "the sequence (mri/sequences/)")
        // TR_ms is every type's key; the others are their types' (mri/sequences/).
        .field("TR_ms", &SequenceSettings::TR_ms, "ms", above(0.0, 1e5), "repetition time")
        .required()
        .field("TE_ms", &SequenceSettings::TE_ms, "ms", sequence_rule(&SequenceSettings::TE_ms),
               "echo time (bSSFP: TR / 2 unless given)")
        .field("flip_deg", &SequenceSettings::flip_deg, "degrees", sequence_rule(&SequenceSettings::flip_deg),
               "flip angle")
        .field("TI_ms", &SequenceSettings::TI_ms, "ms", sequence_rule(&SequenceSettings::TI_ms),
               "inversion time (inversion recovery, MPRAGE)")
        .choice("readout", &SequenceSettings::readout,
                {{"gradient_echo", Readout::gradient_echo}, {"spin_echo", Readout::spin_echo}},
                "inversion recovery's readout")
        .field("echo_spacing_ms", &SequenceSettings::echo_spacing_ms, "ms",
               sequence_rule(&SequenceSettings::echo_spacing_ms),
               "MPRAGE: gradient-echo spacing in the train")
        .field("turbo_factor", &SequenceSettings::turbo_factor, "",
               sequence_rule(&SequenceSettings::turbo_factor), "MPRAGE: echoes per inversion");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<AcquisitionSettings>>& declared_settings<AcquisitionSettings>() {
  static const auto fields = [] {
    using A = AcquisitionSettings;
    SettingsDeclaration<A> d;
    d.shaping(cached_reference_images)
        .field("kspace", &A::kspace, "", "", "simulate k-space truncation (Gibbs ringing)")
        .field("kspace_oversampling", &A::kspace_oversampling, "", range(1, 8),
               "object samples per acquired sample along each axis")
        .field("acquired_voxel_mm", &A::acquired_voxel_mm, "mm", k_positive,
               "acquired voxel size along i, j, k (instead of kspace_oversampling)")
        .scalar_allowed()
        .field("slice_thickness_mm", &A::slice_thickness_mm, "mm", range(0.0, 100.0),
               "rectangular slice profile along k (0: a 3-D acquisition)")
        .field("noise_percent", &A::noise_percent, "percent", range(0.0, 100.0),
               "100 sigma / signal of the reference tissue")
        .field("noise_reference_tissue", &A::noise_reference_tissue, "", "a tissue",
               "the noise's reference tissue")
        .field("bias_percent", &A::bias_percent, "percent", range(0.0, 100.0),
               "peak-to-peak multiplicative bias field")
        .field("coils", &A::coils, "", range(1, 64), "receive coils combined by sum of squares")
        .field("receiver_gain", &A::receiver_gain, "scanner units per proton-density unit", k_positive,
               "the same gain for every image (unset: each sequence's automatic gain)")
        .shaping(no_cached_result)
        .choice("image_datatype", &A::image_datatype,
                {{"float32", ImageDatatype::float32},
                 {"int16", ImageDatatype::int16},
                 {"uint16", ImageDatatype::uint16}},
                "how the image files store voxels");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<TissueRegionSettings>>& declared_settings<TissueRegionSettings>() {
  static const auto fields = [] {
    SettingsDeclaration<TissueRegionSettings> d;
    d.shaping(cached_reference_images)
        .field("organ", &TissueRegionSettings::organ, "", "an organ of an atlas's labels",
               "the organ the region lies in")
        .required()
        .field("label", &TissueRegionSettings::label, "", "a label of that atlas",
               "the atlas label that selects the region's voxels (and names its dseg label unless name does)")
        .required()
        .field("tissue", &TissueRegionSettings::tissue, "", "a tissue", "the region's tissue")
        .required()
        .field(
            "name", &TissueRegionSettings::name, "", "a name",
            "the region's dseg name, when its label names an organ or another region (default: the label)");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<TextureSettings>>& declared_settings<TextureSettings>() {
  static const auto fields = [] {
    using T = TextureSettings;
    SettingsDeclaration<T> d;
    d.shaping(cached_reference_images)
        .choice(
            "source", &T::source,
            {{"none", TextureSource::none}, {"scan", TextureSource::scan}, {"random", TextureSource::random}},
            "where the deviations come from (none: no texture)")
        .field("tissues", &T::tissues, "", "tissues of the phantom", "the textured tissues (empty: all)")
        .field("scan", &T::scan, "", "a NIfTI file covering the anatomy",
               "source: scan or spectrum: scan, the scan (empty: the atlas's T1 scan)")
        .field("T1_gain", &T::T1_gain, "", range(0.0, 5.0), "T1 x exp(-T1_gain d)")
        .field("PD_gain", &T::PD_gain, "", range(0.0, 5.0), "PD x exp(PD_gain d)")
        .field("max_deviation", &T::max_deviation, "", above(0.0, 0.9), "d clamped to +-max_deviation")
        .field("random_sd", &T::random_sd, "", range(0.0, 0.5), "source: random, standard deviation of d")
        .field("correlation_mm", &T::correlation_mm, "mm", range(0.0, 50.0),
               "source: random, standard deviation of the smoothing Gaussian")
        .choice("spectrum", &T::spectrum, {{"given", RandomSpectrum::given}, {"scan", RandomSpectrum::scan}},
                "source: random, the figures: given (random_sd, correlation_mm) or measured per tissue on "
                "the scan")
        .field("match", &T::match, "", "a sequence of the scene",
               "each textured tissue's T1 gain set so that this sequence's signal changes by d (to first "
               "order), instead of T1_gain (empty: T1_gain for every tissue)");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<MriSettings>>& declared_settings<MriSettings>() {
  static const auto fields = [] {
    SettingsDeclaration<MriSettings> d;
    d.shaping(cached_reference_images)
        .field("field_strength_T", &MriSettings::field_strength_T, "T", above(0.0, 11.7),
               "main field strength")
        .required()
        .list("tissues", &MriSettings::tissues, "tissue values replacing or completing the built-in table",
              declared_settings<TissueOverride>())
        .list("sequences", &MriSettings::sequences, "the images to make",
              declared_settings<SequenceSettings>())
        .nested("acquisition", &MriSettings::acquisition, declared_settings<AcquisitionSettings>())
        .list("regions", &MriSettings::regions, "tissue regions within organs (scene key tissue_regions)",
              declared_settings<TissueRegionSettings>())
        .nested("texture", &MriSettings::texture, declared_settings<TextureSettings>())
        .field("seed", &MriSettings::seed, "", "", "seed of the noise and bias field")
        .derived_from("seed")
        .shaping(no_cached_result)
        .field("images", &MriSettings::images, "", "", "the images are written")
        .derived_from("outputs.images")
        .shaping(cached_reference_images)
        .field("parameter_maps", &MriSettings::parameter_maps, "", "", "PD, T1, T2, T2* maps of each state")
        .derived_from("outputs.parameter_maps");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<OutputSettings>>& declared_settings<OutputSettings>() {
  static const auto fields = [] {
    using O = OutputSettings;
    SettingsDeclaration<O> d;
    // What a run writes; only the parameter maps reach a cache (the reference images' entry holds them).
    d.field("subject", &O::subject, "", "a BIDS label", "the dataset's subject label")
        .choice("profile", &O::profile,
                {{"full", OutputProfile::full}, {"benchmark", OutputProfile::benchmark}},
                "the switches' defaults: every output, or none of meshes, vdb, previews, fractions and "
                "parameter_maps")
        .field("images", &O::images, "", "", "MR images")
        .field("labels", &O::labels, "", "", "label volumes")
        .field("fractions", &O::fractions, "", "", "tissue fraction volumes")
        .field("displacement_fields", &O::displacement_fields, "", "", "displacement fields")
        .field("jacobian", &O::jacobian, "", "", "Jacobian determinants")
        .field("landmarks", &O::landmarks, "", "", "landmarks")
        .field("dense_landmarks", &O::dense_landmarks, "points per organ", range(0, 9999),
               "seeded material points per closed organ beside the landmarks, exact in both states (0: none)")
        .field("meshes", &O::meshes, "", "",
               "organ meshes (the solved bodies' tet meshes are written with the displacement fields all the "
               "same)")
        .field("vdb", &O::vdb, "", "", "OpenVDB level sets")
        .field("previews", &O::previews, "", "", "preview images")
        .shaping(cached_reference_images)
        .field("parameter_maps", &O::parameter_maps, "", "", "PD, T1, T2, T2* maps of each state");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<MaterialSettings>>& declared_settings<MaterialSettings>() {
  static const auto fields = [] {
    using M = MaterialSettings;
    SettingsDeclaration<M> d;
    // The solve's stiffness and masses; no cached result holds them.
    d.field("name", &M::name, "", "a safe name", "the material's name, its key")
        .field("youngs_modulus_Pa", &M::youngs_modulus_Pa, "Pa", above(0.0, 1e12), "Young's modulus")
        .required()
        .field("poisson_ratio", &M::poisson_ratio, "", below_half(), "Poisson ratio")
        .required()
        .field("density_kg_m3", &M::density_kg_m3, "kg/m^3", above(0.0, 1e5), "density, for lumped masses");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<SolverSettings>>& declared_settings<SolverSettings>() {
  static const auto fields = [] {
    using V = SolverSettings;
    SettingsDeclaration<V> d;
    d.choice("method", &V::method, by_name(solver_types(), &SolverType::method),
             "the solver (sim/solver_types/); those that step in time need mode dynamic")
        .field("max_iterations", &V::max_iterations, "", range(1, 1000000), "iterations per solve at most")
        .field("relative_energy_tolerance", &V::relative_energy_tolerance, "", range(0.0, 1.0),
               "stop when an iteration lowers the energy by less than this fraction of it")
        .field("position_tolerance_mm", &V::position_tolerance_mm, "mm", non_negative(""),
               "stop when no vertex moves further in one iteration")
        .field("relative_residual_tolerance", &V::relative_residual_tolerance, "", range(0.0, 1.0),
               "converged when the largest free gradient row is at most this fraction of the force scale")
        .field("threads", &V::threads, "", range(0, 1024), "solver threads (0: all cores)");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<LoadSettings>>& declared_settings<LoadSettings>() {
  static const auto fields = [] {
    using L = LoadSettings;
    SettingsDeclaration<L> d;
    // Which organs a load acts on decides the bodies, and so the organs each body's tet mesh
    // carries (sim/sim_settings.hpp, classify_organ_motion); its amounts reach no cached result.
    d.shaping(cached_body_meshes)
        .choice("type", &L::kind, by_name(load_types(), &LoadType::kind),
                "the load type (sim/load_types/), which decides its other keys");
    load_field(d, &L::organs, "the organs it acts on (empty: every organ that is not fixed)");
    load_field(d, &L::organ, "the organ it acts on");
    load_field(d, &L::regions, "the atlas regions whose tets grow (instead of an organ)");
    d.shaping(no_cached_result);
    load_field(d, &L::atlas, "the atlas the regions are of");
    load_field(d, &L::acceleration_m_s2, "the acceleration of the masses");
    load_field(d, &L::displacement_mm, "the displacement of the region's surface points");
    load_field(d, &L::region_center_mm, "the centre of the sphere holding the moved surface points");
    load_field(d, &L::region_radius_mm, "the radius of that sphere");
    load_field(d, &L::rotation_deg, "the turn of the region's points (right-handed)");
    load_field(d, &L::rotation_axis, "the axis of the turn (normalized)");
    load_field(d, &L::rotation_center_mm, "a point of the turn's axis");
    const std::string moving = load_types_reading([](const LoadParameter& p) {
                                 return p.kind == LoadParameter::Kind::motion;
                               }).first;
    d.choice("motion", &L::motion, motion_profiles(), moving + ": how it evolves in a dynamic scene");
    load_field(d, &L::period_s, "the ramp's duration or the sine's period");
    load_field(d, &L::volume_change, "the rest volume's relative change (-0.05: 5 % atrophy)");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<ObstacleSettings>>& declared_settings<ObstacleSettings>() {
  static const auto fields = [] {
    using O = ObstacleSettings;
    SettingsDeclaration<O> d;
    // Obstacles do not make an organ simulated: they reach no cached result.
    d.choice("type", &O::shape,
             {{"half_space", ObstacleShape::half_space}, {"sphere", ObstacleShape::sphere}},
             "the obstacle's shape")
        .required()
        .field("point_mm", &O::point_mm, "mm", k_coordinate,
               "half_space: a point of its plane; sphere: its centre (scene key center_mm)")
        .field("normal", &O::normal, "", range(-1e6, 1e6),
               "half_space: unit normal out of the obstacle, towards the tissue")
        .bounds_note("not zero")
        .field("radius_mm", &O::radius_mm, "mm", k_positive, "sphere: its radius")
        .field("displacement_mm", &O::displacement_mm, "mm", range(-1000.0, 1000.0),
               "how far it moves: over the load steps, or by its motion in a dynamic scene")
        .choice("motion", &O::motion, motion_profiles(), "how it moves in a dynamic scene")
        .field("period_s", &O::period_s, "s", k_positive, "the ramp's duration or the sine's period");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<CollisionSettings>>& declared_settings<CollisionSettings>() {
  static const auto fields = [] {
    SettingsDeclaration<CollisionSettings> d;
    d.field("organs", &CollisionSettings::organs, "", "two organ names",
            "two simulated organs whose surfaces may not pass through each other");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<OrganMechanics>>& declared_settings<OrganMechanics>() {
  static const auto fields = [] {
    using O = OrganMechanics;
    SettingsDeclaration<O> d;
    // Whether an organ is solid decides which organs a growth simulates; its material decides
    // which nested organs a body's mesh merges (anatomy.tet_interfaces: materials).
    d.shaping(cached_body_meshes)
        .field("material", &O::material, "", "a material of the scene's materials", "the organ's material")
        .field("solid", &O::solid, "", "", "tetrahedralized interior, or a surface simulated as a shell")
        .shaping(no_cached_result)
        .field("thickness_mm", &O::thickness_mm, "mm", above(0.0, 1000.0), "a shell's wall thickness")
        .field("enclosed_volume_tolerance", &O::enclosed_volume_tolerance, "", range(0.0, 0.5),
               "a closed shell's enclosed volume kept within this fraction of rest (unset: free)");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<HeadScaleSettings>>& declared_settings<HeadScaleSettings>() {
  static const auto fields = [] {
    using H = HeadScaleSettings;
    SettingsDeclaration<H> d;
    // Applied to the deformed positions after the solve: the template (anatomy, reference state,
    // bodies' tet meshes) is the same for every size.
    d.field("scale", &H::scale, "", range(0.7, 1.3),
            "the linear scale of the whole head after the solve (volumes change by its cube)")
        .field("axes", &H::axes, "", range(0.8, 1.25),
               "shape: per-axis factors (x, y, z) on top of the scale, about the centre")
        .field("center_mm", &H::center_mm, "mm", k_coordinate,
               "the point that stays (unset: the centre of the box of the organs at rest)");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<DeformationSettings>>& declared_settings<DeformationSettings>() {
  static const auto fields = [] {
    using D = DeformationSettings;
    SettingsDeclaration<D> d;
    // The mode, the fixed organs and the loads decide which organs are simulated, and so the
    // bodies whose tet meshes the body mesh cache keeps; nothing of the deformation reaches the
    // anatomy, the reference state or its images.
    d.shaping(cached_body_meshes)
        .choice("mode", &D::mode,
                {{"none", DeformationMode::none},
                 {"quasi_static", DeformationMode::quasi_static},
                 {"dynamic", DeformationMode::dynamic}},
                "none: the deformed state is the reference; quasi_static: equilibrium; dynamic: frames")
        .required()
        .shaping(no_cached_result)
        .nested("solver", &D::solver, declared_settings<SolverSettings>())
        .field("time_step_s", &D::time_step_s, "s", range(1e-6, 10.0), "time step (dynamic)")
        .field("frames", &D::frames, "", range(1, 100000), "frames (dynamic)")
        .shaping(cached_body_meshes)
        .custom<std::vector<std::string>>("fixed", &D::fixed, "list of text", "", "organs held in place",
                                          SettingValue<std::vector<std::string>>::exact,
                                          SettingValue<std::vector<std::string>>::shown,
                                          [](std::vector<std::string>& names) {
                                            // An organ freed, or one more held: the organs' motion changes.
                                            if (names.empty())
                                              names.emplace_back();
                                            else
                                              names.pop_back();
                                          })
        .list("loads", &D::loads, "the loads", declared_settings<LoadSettings>())
        .list("obstacles", &D::obstacles, "rigid obstacles no simulated vertex may enter",
              declared_settings<ObstacleSettings>())
        .list("collisions", &D::collisions, "pairs of organs in frictionless contact",
              declared_settings<CollisionSettings>())
        .shaping(no_cached_result)
        .field("load_steps", &D::load_steps, "", range(1, 10000),
               "quasi-static: loads and obstacles applied in this many equal increments")
        .choice("volume", &D::volume,
                {{"per_tet", VolumeFormulation::tet},
                 {"tet_groups", VolumeFormulation::tet_group},
                 {"tet_groups_and_tets", VolumeFormulation::tet_group_and_tet},
                 {"vertex_stars", VolumeFormulation::vertex_star}},
                "where the solid bodies' bulk term lives")
        .nested("head_scale", &D::head_scale, declared_settings<HeadScaleSettings>())
        .list("materials", &D::materials, "the elastic materials organs refer to",
              declared_settings<MaterialSettings>())
        .list("organs", &D::organs, "what the deformation reads of each organ, in scene order",
              declared_settings<OrganMechanics>())
        .field("region_atlas", &D::region_atlas, "", "",
               "the atlas whose regions growth loads name (read by the run; not a scene key)")
        .not_in_scene_file();
    // derived_from() and key_elsewhere() mark one field: a list's are its count and its elements'.
    std::vector<SettingField<D>> all = d.fields();
    for (SettingField<D>& f : all) {
      if (in_list(f, "materials")) {
        f.in_section = false;
        f.help += " (scene key materials)";
      } else if (in_list(f, "organs")) {
        f.derived = true;
        f.help += " (set by the scene from anatomy.organs)";
      }
    }
    return all;
  }();
  return fields;
}

// Every data member of each settings struct, in the struct's order. A member added to a struct
// stops the build here ("N names provided, but the struct has N + 1 members"): declare it above
// with the cached results it shapes, then name it here.

std::vector<const void*> settings_members(const GridSettings& s) {
  const auto& [field_of_view, voxel_size, center, orientation] = s;
  return {&field_of_view, &voxel_size, &center, &orientation};
}

std::vector<const void*> settings_members(const ShapeSettings& s) {
  const auto& [kind, center, radii, rotation, e1, e2, size, cells, file, atlas, label, labels, smoothing] = s;
  return {&kind,  &center, &radii, &rotation, &e1,     &e2,       &size,
          &cells, &file,   &atlas, &label,    &labels, &smoothing};
}

std::vector<const void*> settings_members(const OrganSettings& s) {
  const auto& [name, tissue, material, inside, solid, triangles, shape, thickness, tolerance] = s;
  return {&name, &tissue, &material, &inside, &solid, &triangles, &shape, &thickness, &tolerance};
}

std::vector<const void*> settings_members(const AnatomySettings& s) {
  const auto& [variation, triangles, tet_size, facet_distance, interfaces, organs, seed] = s;
  return {&variation, &triangles, &tet_size, &facet_distance, &interfaces, &organs, &seed};
}

std::vector<const void*> settings_members(const VoxelizationSettings& s) {
  const auto& [supersampling, tolerance, gap_tissue, from_tessellation, deformed, keep_level_sets, labels,
               fractions, fields, jacobian, landmarks, dense_landmarks, gap_fill, bounds] = s;
  return {&supersampling, &tolerance, &gap_tissue, &from_tessellation, &deformed,  &keep_level_sets,
          &labels,        &fractions, &fields,     &jacobian,          &landmarks, &dense_landmarks,
          &gap_fill,      &bounds};
}

std::vector<const void*> settings_members(const TissueOverride& s) {
  const auto& [tissue, T1, T2, T2star, PD] = s;
  return {&tissue, &T1, &T2, &T2star, &PD};
}

std::vector<const void*> settings_members(const SequenceSettings& s) {
  const auto& [name, kind, TR, TE, flip, TI, readout, echo_spacing, turbo_factor] = s;
  return {&name, &kind, &TR, &TE, &flip, &TI, &readout, &echo_spacing, &turbo_factor};
}

std::vector<const void*> settings_members(const AcquisitionSettings& s) {
  const auto& [kspace, oversampling, acquired_voxel, slice, noise, noise_tissue, bias, coils, gain,
               datatype] = s;
  return {&kspace,       &oversampling, &acquired_voxel, &slice, &noise,
          &noise_tissue, &bias,         &coils,          &gain,  &datatype};
}

std::vector<const void*> settings_members(const TissueRegionSettings& s) {
  const auto& [organ, label, tissue, name] = s;
  return {&organ, &label, &tissue, &name};
}

std::vector<const void*> settings_members(const TextureSettings& s) {
  const auto& [source, tissues, scan, T1_gain, PD_gain, max_deviation, random_sd, correlation, spectrum,
               match] = s;
  return {&source,        &tissues,   &scan,        &T1_gain,  &PD_gain,
          &max_deviation, &random_sd, &correlation, &spectrum, &match};
}

std::vector<const void*> settings_members(const MriSettings& s) {
  const auto& [field_strength, tissues, sequences, acquisition, regions, texture, seed, images,
               parameter_maps] = s;
  return {&field_strength, &tissues, &sequences, &acquisition,   &regions,
          &texture,        &seed,    &images,    &parameter_maps};
}

std::vector<const void*> settings_members(const OutputSettings& s) {
  const auto& [subject, profile, images, labels, fractions, fields, jacobian, landmarks, dense_landmarks,
               meshes, vdb, previews, maps] = s;
  return {&subject,   &profile,         &images, &labels, &fractions, &fields, &jacobian,
          &landmarks, &dense_landmarks, &meshes, &vdb,    &previews,  &maps};
}

std::vector<const void*> settings_members(const MaterialSettings& s) {
  const auto& [name, youngs_modulus, poisson_ratio, density] = s;
  return {&name, &youngs_modulus, &poisson_ratio, &density};
}

std::vector<const void*> settings_members(const SolverSettings& s) {
  const auto& [method, iterations, energy, position, residual, threads] = s;
  return {&method, &iterations, &energy, &position, &residual, &threads};
}

std::vector<const void*> settings_members(const LoadSettings& s) {
  const auto& [kind, organs, acceleration, organ, displacement, region_center, region_radius, rotation, axis,
               rotation_center, motion, period, volume_change, regions, atlas] = s;
  return {&kind,          &organs,        &acceleration,  &organ,   &displacement,
          &region_center, &region_radius, &rotation,      &axis,    &rotation_center,
          &motion,        &period,        &volume_change, &regions, &atlas};
}

std::vector<const void*> settings_members(const ObstacleSettings& s) {
  const auto& [shape, point, normal, radius, displacement, motion, period] = s;
  return {&shape, &point, &normal, &radius, &displacement, &motion, &period};
}

std::vector<const void*> settings_members(const CollisionSettings& s) {
  const auto& [organs] = s;
  return {&organs};
}

std::vector<const void*> settings_members(const OrganMechanics& s) {
  const auto& [material, solid, thickness, tolerance] = s;
  return {&material, &solid, &thickness, &tolerance};
}

std::vector<const void*> settings_members(const HeadScaleSettings& s) {
  const auto& [scale, axes, center] = s;
  return {&scale, &axes, &center};
}

std::vector<const void*> settings_members(const DeformationSettings& s) {
  const auto& [mode, solver, time_step, frames, fixed, loads, obstacles, collisions, load_steps, volume,
               head_scale, materials, organs, region_atlas] = s;
  return {&mode,       &solver,     &time_step, &frames,     &fixed,     &loads,  &obstacles,
          &collisions, &load_steps, &volume,    &head_scale, &materials, &organs, &region_atlas};
}

namespace {

std::string keys_text(unsigned keys) {
  std::string out;
  if (keys & cached_anatomy) out += "anatomy";
  if (keys & cached_reference_state) out += std::string(out.empty() ? "" : ", ") + "reference state";
  if (keys & cached_reference_images) out += std::string(out.empty() ? "" : ", ") + "reference images";
  if (keys & cached_body_meshes) out += std::string(out.empty() ? "" : ", ") + "body mesh";
  return out.empty() ? "no cache" : out;
}

template <typename S>
void add_rows(std::vector<std::string>& rows, const std::string& section, const S& value) {
  const S defaults{};
  for (const SettingField<S>& f : declared_settings<S>()) {
    std::string row = section + "." + f.name + " = " + f.shown(value);
    if (!f.unit.empty()) row += " " + f.unit;
    row += "  (" + f.type;
    if (!f.bounds.empty()) row += ", " + f.bounds;
    if (!f.derived && f.name.find("[]") == std::string::npos) row += ", default " + f.shown(defaults);
    row += "; shapes " + keys_text(f.keys) + ")  " + f.help;
    rows.push_back(row);
  }
}

} // namespace

std::vector<std::string> settings_table(const Scene& scene) {
  std::vector<std::string> rows;
  add_rows(rows, "grid", scene.grid);
  add_rows(rows, "anatomy", scene.anatomy);
  add_rows(rows, "deformation", scene.deformation);
  add_rows(rows, "voxelization", scene.voxelization);
  add_rows(rows, "mri", scene.mri);
  add_rows(rows, "outputs", scene.outputs);
  return rows;
}

} // namespace phantasm
