#include "scene/settings_declarations.hpp"

#include "anatomy/shape_source.hpp"
#include "mri/sequence_type.hpp"

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

namespace {

const char* const k_coordinate = "-1e5 to 1e5";
const char* const k_positive = "above 0";
const char* const k_time = "0 to 1e5";
const char* const k_triangles = "20 to 200000";

/// The members of a registry (sequence types, shape sources) by name.
template <typename Member>
auto kinds_by_name(const std::vector<const Member*>& members) {
  std::vector<std::pair<std::string, decltype(Member::kind)>> kinds;
  for (const Member* member : members)
    kinds.emplace_back(member->name, member->kind);
  return kinds;
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
        .field("voxel_size_mm", &GridSettings::voxel_size_mm, "mm", k_positive, "voxel size along i, j, k")
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
        .field("center_mm", &ShapeSettings::center_mm, "mm", k_coordinate, "centre of an analytic shape, RAS")
        .field("radii_mm", &ShapeSettings::radii_mm, "mm", k_positive,
               "semi-axes of an ellipsoid or superquadric before rotation")
        .field("rotation_deg", &ShapeSettings::rotation_deg, "degrees", "",
               "rotations about x, then y, then z")
        .field("exponent_1", &ShapeSettings::exponent_1, "", "0.1 to 4",
               "superquadric north-south exponent (1: ellipsoid)")
        .field("exponent_2", &ShapeSettings::exponent_2, "", "0.1 to 4",
               "superquadric east-west exponent (1: ellipsoid)")
        .field("size_mm", &ShapeSettings::size_mm, "mm", k_positive,
               "box edge lengths; sheet: x and y extent")
        .field("cells", &ShapeSettings::cells, "", "1 to 1000",
               "box: hexahedral cells per axis (5 tets each); sheet: x, y")
        .field("file", &ShapeSettings::file, "", "", "mesh or label volume, relative to the scene's folder")
        .field("atlas", &ShapeSettings::atlas, "", "colin27", "label volume made from installed data")
        .field("label", &ShapeSettings::label, "", "1 to 65535",
               "label volume: the first label given by number")
        .field("labels", &ShapeSettings::labels, "", "", "label volume: every label, by number or name")
        .field("smoothing_mm", &ShapeSettings::smoothing_mm, "mm", "0 to 10",
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
        .field("tissue", &OrganSettings::tissue, "", "a safe name", "its tissue")
        .field("material", &OrganSettings::material, "", "", "a material of the scene's materials")
        .field("inside", &OrganSettings::inside, "", "", "the organ containing it; empty for the outermost")
        .field("solid", &OrganSettings::solid, "", "", "tetrahedralized interior, or a surface only")
        .field("base_mesh_triangles", &OrganSettings::base_mesh_triangles, "", k_triangles,
               "this organ's patch base mesh size (0: anatomy.base_mesh_triangles)")
        .nested("shape", &OrganSettings::shape, declared_settings<ShapeSettings>())
        .field("thickness_mm", &OrganSettings::thickness_mm, "mm", "above 0 to 1000",
               "wall thickness of a surface organ simulated as a shell")
        .field("enclosed_volume_tolerance", &OrganSettings::enclosed_volume_tolerance, "", "0 to 0.5",
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
        .field("variation", &AnatomySettings::variation, "relative size", "0 to 0.3",
               "seeded relative variation of organ sizes (0: exact)")
        .field("base_mesh_triangles", &AnatomySettings::base_mesh_triangles, "", k_triangles,
               "patch base mesh size per organ (the anatomy's accuracy knob)")
        .field("tet_size_mm", &AnatomySettings::tet_size_mm, "mm", "0.5 to 500",
               "element size of one conforming tet mesh per simulated body (0: each organ's own mesh)")
        .field("tet_facet_distance_mm", &AnatomySettings::tet_facet_distance_mm, "mm", "0.05 to 100",
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
        .field("supersampling", &V::supersampling, "", "1 to 16",
               "samples per voxel edge of the partial-volume fractions")
        .field("tessellation_tolerance_mm", &V::tessellation_tolerance_mm, "mm", "above 0 to 10",
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
        .field("PD", &TissueOverride::PD, "units of CSF proton density", "0 to 1.5", "proton density");
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
        .choice("type", &SequenceSettings::kind, kinds_by_name(sequence_types()),
                "the sequence (mri/sequences/)")
        .field("TR_ms", &SequenceSettings::TR_ms, "ms", k_time, "repetition time")
        .field("TE_ms", &SequenceSettings::TE_ms, "ms", "above 0 to 1e5",
               "echo time (bSSFP: TR / 2 unless given)")
        .field("flip_deg", &SequenceSettings::flip_deg, "degrees", "0 to 180", "flip angle")
        .field("TI_ms", &SequenceSettings::TI_ms, "ms", k_time, "inversion time (inversion recovery, MPRAGE)")
        .choice("readout", &SequenceSettings::readout,
                {{"gradient_echo", Readout::gradient_echo}, {"spin_echo", Readout::spin_echo}},
                "inversion recovery's readout")
        .field("echo_spacing_ms", &SequenceSettings::echo_spacing_ms, "ms", k_time,
               "MPRAGE: gradient-echo spacing in the train")
        .field("turbo_factor", &SequenceSettings::turbo_factor, "", "1 to 1024",
               "MPRAGE: echoes per inversion");
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
        .field("kspace_oversampling", &A::kspace_oversampling, "", "1 to 8",
               "object samples per acquired sample along each axis")
        .field("acquired_voxel_mm", &A::acquired_voxel_mm, "mm", k_positive,
               "acquired voxel size along i, j, k (instead of kspace_oversampling)")
        .field("slice_thickness_mm", &A::slice_thickness_mm, "mm", "0 to 100",
               "rectangular slice profile along k (0: a 3-D acquisition)")
        .field("noise_percent", &A::noise_percent, "percent", "0 to 100",
               "100 sigma / signal of the reference tissue")
        .field("noise_reference_tissue", &A::noise_reference_tissue, "", "a tissue",
               "the noise's reference tissue")
        .field("bias_percent", &A::bias_percent, "percent", "0 to 100",
               "peak-to-peak multiplicative bias field")
        .field("coils", &A::coils, "", "1 to 64", "receive coils combined by sum of squares")
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
        .field("label", &TissueRegionSettings::label, "", "a label of that atlas",
               "the atlas label that selects the region's voxels (and names its dseg label)")
        .field("tissue", &TissueRegionSettings::tissue, "", "a tissue", "the region's tissue");
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
               "source: scan, the scan (empty: the atlas's T1 scan)")
        .field("T1_gain", &T::T1_gain, "", "0 to 5", "T1 x exp(-T1_gain d)")
        .field("PD_gain", &T::PD_gain, "", "0 to 5", "PD x exp(PD_gain d)")
        .field("max_deviation", &T::max_deviation, "", "above 0 to 0.9", "d clamped to +-max_deviation")
        .field("random_sd", &T::random_sd, "", "0 to 0.5", "source: random, standard deviation of d")
        .field("correlation_mm", &T::correlation_mm, "mm", "0 to 50",
               "source: random, standard deviation of the smoothing Gaussian");
    return d.fields();
  }();
  return fields;
}

template <>
const std::vector<SettingField<MriSettings>>& declared_settings<MriSettings>() {
  static const auto fields = [] {
    SettingsDeclaration<MriSettings> d;
    d.shaping(cached_reference_images)
        .field("field_strength_T", &MriSettings::field_strength_T, "T", "above 0 to 11.7",
               "main field strength")
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
        .field("dense_landmarks", &O::dense_landmarks, "points per organ", "0 to 9999",
               "seeded material points per closed organ beside the landmarks, exact in both states (0: none)")
        .field("meshes", &O::meshes, "", "", "organ meshes")
        .field("vdb", &O::vdb, "", "", "OpenVDB level sets")
        .field("previews", &O::previews, "", "", "preview images")
        .shaping(cached_reference_images)
        .field("parameter_maps", &O::parameter_maps, "", "", "PD, T1, T2, T2* maps of each state");
    return d.fields();
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
  const auto& [organ, label, tissue] = s;
  return {&organ, &label, &tissue};
}

std::vector<const void*> settings_members(const TextureSettings& s) {
  const auto& [source, tissues, scan, T1_gain, PD_gain, max_deviation, random_sd, correlation] = s;
  return {&source, &tissues, &scan, &T1_gain, &PD_gain, &max_deviation, &random_sd, &correlation};
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

namespace {

std::string keys_text(unsigned keys) {
  std::string out;
  if (keys & cached_anatomy) out += "anatomy";
  if (keys & cached_reference_state) out += std::string(out.empty() ? "" : ", ") + "reference state";
  if (keys & cached_reference_images) out += std::string(out.empty() ? "" : ", ") + "reference images";
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
  add_rows(rows, "voxelization", scene.voxelization);
  add_rows(rows, "mri", scene.mri);
  add_rows(rows, "outputs", scene.outputs);
  return rows;
}

} // namespace phantasm
