// Mitsuba 3 XML scenes: the importer (core/scene/mitsuba_scene.h) element by element and error by error,
// the exporter's round trip (export -> import gives the original scene), the shared Cornell box XML, and
// `twinray compare` against Mitsuba itself when it is installed (scripts/setup-mitsuba.sh).

#include "render_test_util.h"
#include "scene_test_files.h"

#include "harness/compare/compare_run.h"
#include "harness/converge/peer_series.h"
#include "core/image/image_io.h"
#include "core/scene/mitsuba_export.h"
#include "core/scene/mitsuba_scene.h"
#include "core/scene/scene_loader.h"
#include "core/util/input_error.h"

#include <glm/geometric.hpp>
#include <gtest/gtest.h>

#include <cstdlib>
#include <string>

namespace twinray {
namespace {

using namespace twinray::test;
using twinray::testing::TempFolder;

constexpr const char* kTriObj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";

// A complete scene around `body` (inserted after the sensor); line 1 is <scene>, the sensor takes lines 2-9.
std::string xml_scene(const std::string& body, const std::string& film_extra = "") {
  return "<scene version=\"3.0.0\">\n"
         "  <sensor type=\"perspective\">\n"
         "    <float name=\"fov\" value=\"40\"/>\n"
         "    <transform name=\"to_world\"><lookat origin=\"0, 0, 5\" target=\"0, 0, 0\" up=\"0, 1, 0\"/></transform>\n"
         "    <sampler type=\"independent\"><integer name=\"sample_count\" value=\"8\"/></sampler>\n"
         "    <film type=\"hdrfilm\"><integer name=\"width\" value=\"32\"/><integer name=\"height\" value=\"16\"/>\n"
         "      <rfilter type=\"box\"/>" + film_extra + "\n"
         "    </film>\n"
         "  </sensor>\n" +
         body + "</scene>\n";
}

Scene parse_in(const TempFolder& folder, const std::string& text) {
  folder.write("tri.obj", kTriObj);
  return parse_mitsuba_scene(text, folder.path() / "scene.xml");
}

TEST(MitsubaImport, EverySupportedElement) {
  TempFolder folder;
  const std::string body = R"(  <default name="r" value="0.25"/>
  <integrator type="path"><integer name="max_depth" value="7"/><integer name="rr_depth" value="3"/></integrator>
  <bsdf type="twosided" id="white"><bsdf type="diffuse"><rgb name="reflectance" value="$r, 0.5, 0.75"/></bsdf></bsdf>
  <bsdf type="diffuse" id="grey"><float name="reflectance" value="0.4"/></bsdf>
  <bsdf type="conductor" id="chrome"><rgb name="specular_reflectance" value="0.9"/></bsdf>
  <bsdf type="dielectric" id="glass"><string name="int_ior" value="diamond"/><float name="ext_ior" value="1.2"/></bsdf>
  <shape type="obj" id="tri"><string name="filename" value="tri.obj"/><boolean name="face_normals" value="true"/>
    <transform name="to_world"><scale value="2"/><translate x="1" y="0" z="0"/></transform><ref id="white"/></shape>
  <shape type="rectangle" id="lamp"><boolean name="flip_normals" value="true"/><ref id="grey"/>
    <emitter type="area"><rgb name="radiance" value="10, 9, 8"/></emitter></shape>
  <shape type="cube" id="box"><ref name="bsdf" id="chrome"/>
    <transform name="to_world"><matrix value="1 0 0 0  0 1 0 3  0 0 1 0  0 0 0 1"/></transform></shape>
  <shape type="sphere" id="ball"><point name="center" x="0" y="1" z="0"/><float name="radius" value="0.5"/>
    <transform name="to_world"><rotate y="1" angle="90"/><scale value="2"/></transform><ref id="glass"/></shape>
  <shape type="sphere" id="plain"><point name="center" value="5, 0, 0"/></shape>
  <emitter type="constant"><spectrum name="radiance" value="0.5"/></emitter>
)";
  const Scene s = parse_in(folder, xml_scene(body));
  EXPECT_EQ(s.camera.width, 32);
  EXPECT_EQ(s.camera.height, 16);
  // fov_axis defaults to x: the vertical field of view of a 2:1 image is narrower.
  EXPECT_NEAR(s.camera.vfov_deg, 2.0 * std::atan(std::tan(20.0 * std::numbers::pi / 180.0) / 2.0) * 180.0 / std::numbers::pi, 1e-4);
  EXPECT_EQ(s.camera.position, glm::vec3(0, 0, 5));
  EXPECT_NEAR(glm::length(glm::normalize(s.camera.look_at - s.camera.position) - glm::vec3(0, 0, -1)), 0.0f, 1e-6f);
  EXPECT_NEAR(glm::length(s.camera.up - glm::vec3(0, 1, 0)), 0.0f, 1e-6f);
  EXPECT_EQ(s.render.spp, 8);
  EXPECT_EQ(s.render.max_depth, 7);
  EXPECT_EQ(s.render.rr_depth, 3);
  ASSERT_EQ(s.shapes.size(), 5u);
  const Material& white = s.material_of(0);
  EXPECT_EQ(white.type, MaterialType::Diffuse);
  EXPECT_EQ(white.albedo, glm::vec3(0.25f, 0.5f, 0.75f));
  EXPECT_TRUE(white.two_sided);
  const Material& lamp = s.material_of(1);
  EXPECT_EQ(lamp.type, MaterialType::Emissive);
  EXPECT_EQ(lamp.radiance, glm::vec3(10, 9, 8));
  EXPECT_EQ(lamp.albedo, glm::vec3(0.4f));
  EXPECT_FALSE(lamp.two_sided);
  EXPECT_EQ(s.material_of(2).type, MaterialType::Mirror);
  EXPECT_EQ(s.material_of(2).reflectance, glm::vec3(0.9f));
  EXPECT_FALSE(s.material_of(2).two_sided);
  EXPECT_EQ(s.material_of(3).type, MaterialType::Glass);
  EXPECT_FLOAT_EQ(s.material_of(3).ior, static_cast<float>(2.419 / 1.2));
  EXPECT_EQ(s.material_of(4).type, MaterialType::Diffuse);  // Mitsuba's default BSDF
  EXPECT_EQ(s.material_of(4).albedo, glm::vec3(0.5f));
  // Geometry: the triangle scaled then moved; the rectangle flipped (front faces -Z); the cube moved up.
  const TriangleMesh& tri = s.geometry.meshes[0];
  EXPECT_EQ(tri.positions[1], glm::vec3(3, 0, 0));
  EXPECT_EQ(tri.positions[2], glm::vec3(1, 2, 0));
  const TriangleMesh& rect = s.geometry.meshes[1];
  ASSERT_EQ(rect.indices.size(), 2u);
  const glm::uvec3 t = rect.indices[0];
  EXPECT_LT(glm::cross(rect.positions[t.y] - rect.positions[t.x], rect.positions[t.z] - rect.positions[t.x]).z, 0.0f);
  const Bounds3 cube = s.geometry.meshes[2].bounds();
  EXPECT_EQ(cube.lo, glm::vec3(-1, 2, -1));
  EXPECT_EQ(cube.hi, glm::vec3(1, 4, 1));
  EXPECT_EQ(s.geometry.meshes[2].indices.size(), 12u);
  ASSERT_EQ(s.geometry.spheres.size(), 2u);
  EXPECT_NEAR(glm::length(s.geometry.spheres[0].center - glm::vec3(0, 2, 0)), 0.0f, 1e-6f);
  EXPECT_FLOAT_EQ(s.geometry.spheres[0].radius, 1.0f);
  EXPECT_EQ(s.geometry.spheres[1].center, glm::vec3(5, 0, 0));
  EXPECT_EQ(s.environment.type, EnvironmentType::Constant);
  EXPECT_EQ(s.environment.radiance, glm::vec3(0.5f));
}

TEST(MitsubaImport, FovAxesAndEnvmapRotation) {
  TempFolder folder;
  write_exr(folder.path() / "sky.exr", Image(8, 4, 3));
  for (const auto& [axis, expected] : std::initializer_list<std::pair<const char*, double>>{
           {"y", 40.0}, {"smaller", 40.0}, {"larger", 2.0 * std::atan(std::tan(20.0 * std::numbers::pi / 180.0) / 2.0) * 180.0 / std::numbers::pi},
           {"diagonal", 2.0 * std::atan(std::tan(20.0 * std::numbers::pi / 180.0) / std::sqrt(5.0)) * 180.0 / std::numbers::pi}}) {
    std::string text = xml_scene(R"(  <emitter type="envmap"><string name="filename" value="sky.exr"/><float name="scale" value="2"/>
    <transform name="to_world"><rotate y="1" angle="210"/></transform></emitter>
)");
    text.replace(text.find("<float name=\"fov\" value=\"40\"/>"), 0, std::string("<string name=\"fov_axis\" value=\"") + axis + "\"/>");
    const Scene s = parse_in(folder, text);
    EXPECT_NEAR(s.camera.vfov_deg, expected, 1e-4) << axis;
    EXPECT_EQ(s.environment.type, EnvironmentType::Image);
    EXPECT_EQ(s.environment.scale, 2.0f);
    EXPECT_NEAR(s.environment.rotation_deg, 30.0f, 1e-4f);  // Mitsuba's angle minus 180 (docs/mitsuba.md)
    EXPECT_EQ(s.environment.filter, EnvironmentFilter::Bilinear);  // Mitsuba's envmap lookup
  }
}

struct ImportError {
  const char* name;
  std::string text;
  int line;
  const char* message;  // a substring of the error
};

TEST(MitsubaImport, ErrorsNameTheElementAndLine) {
  // Lines: 1 <scene>, 2-9 the sensor, 10 the first line of the body.
  const std::vector<ImportError> cases = {
      {"syntax", xml_scene("  <shape type=\"cube\">\n"), 11, "XML syntax error"},
      {"root", "<scen version=\"3.0.0\"/>\n", 1, "expected <scene>"},
      {"old version", "<scene version=\"0.6.0\">\n</scene>\n", 1, "version '0.6.0' is not supported"},
      {"no sensor", "<scene version=\"3.0.0\">\n</scene>\n", 1, "no <sensor>"},
      {"unknown top element", xml_scene("  <texture type=\"bitmap\"/>\n"), 10, "<texture> is not supported"},
      {"integrator", xml_scene("  <integrator type=\"volpath\"/>\n"), 10, "integrator 'volpath'"},
      {"hide emitters", xml_scene("  <integrator type=\"path\">\n    <boolean name=\"hide_emitters\" value=\"true\"/>\n  </integrator>\n"), 10, "hide_emitters"},
      {"unknown property", xml_scene("  <integrator type=\"path\">\n    <float name=\"max_time\" value=\"3\"/>\n  </integrator>\n"), 11, "'max_time' is not supported"},
      {"bad integer", xml_scene("  <integrator type=\"path\">\n    <integer name=\"max_depth\" value=\"x\"/>\n  </integrator>\n"), 11, "max_depth"},
      {"undefined parameter", xml_scene("  <integrator type=\"path\">\n    <integer name=\"max_depth\" value=\"$depth\"/>\n  </integrator>\n"), 11, "'$depth' is not defined"},
      {"gaussian", xml_scene("").replace(xml_scene("").find("<rfilter type=\"box\"/>"), 21, "<rfilter type=\"gaussian\"/>"), 7, "rfilter 'gaussian'"},
      {"bsdf type", xml_scene("  <bsdf type=\"roughplastic\" id=\"p\"/>\n"), 10, "bsdf 'roughplastic'"},
      {"conductor material", xml_scene("  <bsdf type=\"conductor\" id=\"c\">\n    <string name=\"material\" value=\"Au\"/>\n  </bsdf>\n"), 10, "conductor material 'Au'"},
      {"reflectance above 1", xml_scene("  <bsdf type=\"diffuse\" id=\"d\">\n    <rgb name=\"reflectance\" value=\"1.5, 0, 0\"/>\n  </bsdf>\n"), 10, "at most 1"},
      {"two-sided pair", xml_scene("  <bsdf type=\"twosided\" id=\"t\">\n    <bsdf type=\"diffuse\"/>\n    <bsdf type=\"diffuse\"/>\n  </bsdf>\n"), 10, "different one per side"},
      {"unknown ior", xml_scene("  <bsdf type=\"dielectric\" id=\"g\">\n    <string name=\"int_ior\" value=\"unobtainium\"/>\n  </bsdf>\n"), 11, "unknown index of refraction"},
      {"no id", xml_scene("  <bsdf type=\"diffuse\"/>\n"), 10, "needs an id"},
      {"smooth normals", xml_scene("  <shape type=\"obj\">\n    <string name=\"filename\" value=\"tri.obj\"/>\n  </shape>\n"), 10, "face_normals"},
      {"missing mesh", xml_scene("  <shape type=\"obj\">\n    <string name=\"filename\" value=\"nope.obj\"/>\n    <boolean name=\"face_normals\" value=\"true\"/>\n  </shape>\n"), -1, "mesh referenced at line 10"},
      {"shape type", xml_scene("  <shape type=\"cylinder\"/>\n"), 10, "shape 'cylinder'"},
      {"unknown ref", xml_scene("  <shape type=\"cube\">\n    <ref id=\"nothing\"/>\n  </shape>\n"), 11, "no bsdf with id 'nothing'"},
      {"emitter on glass", xml_scene("  <shape type=\"cube\">\n    <bsdf type=\"dielectric\"/>\n    <emitter type=\"area\"/>\n  </shape>\n"), 10, "area emitter on a conductor or dielectric"},
      {"sphere flip", xml_scene("  <shape type=\"sphere\">\n    <boolean name=\"flip_normals\" value=\"true\"/>\n  </shape>\n"), 10, "flip_normals on a sphere"},
      {"sheared sphere", xml_scene("  <shape type=\"sphere\">\n    <transform name=\"to_world\"><scale x=\"2\"/></transform>\n  </shape>\n"), 10, "sphere"},
      {"point light", xml_scene("  <emitter type=\"point\"/>\n"), 10, "emitter 'point'"},
      {"sphere beyond float", xml_scene("  <shape type=\"sphere\"><float name=\"radius\" value=\"3e38\"/>\n    <transform name=\"to_world\"><scale value=\"10\"/></transform></shape>\n"), 10, "outside float range"},
      {"tilted envmap", xml_scene("  <emitter type=\"constant\"/>\n  <emitter type=\"constant\"/>\n"), 11, "second environment"},
      {"projective matrix", xml_scene("  <shape type=\"cube\">\n    <transform name=\"to_world\">\n      <matrix value=\"1 0 0 0 0 1 0 0 0 0 1 0 0 0 1 1\"/>\n    </transform>\n  </shape>\n"), 12, "last row must be 0 0 0 1"},
      {"transform op", xml_scene("  <shape type=\"cube\">\n    <transform name=\"to_world\">\n      <shear value=\"1\"/>\n    </transform>\n  </shape>\n"), 12, "<shear> inside <transform>"},
      {"far clip", xml_scene("  <shape type=\"cube\"><transform name=\"to_world\"><translate z=\"-20000\"/></transform></shape>\n"), 2, "far_clip"},
      {"near clip", [] { std::string t = xml_scene(""); t.replace(t.find("<float name=\"fov\""), 0, "<float name=\"near_clip\" value=\"1\"/>"); return t; }(), 2, "near_clip"},
  };
  for (const ImportError& c : cases) {
    TempFolder folder;
    try {
      (void)parse_in(folder, c.text);
      ADD_FAILURE() << c.name << ": no error";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.message), std::string::npos) << c.name << ": " << e.what();
      if (c.line > 0) {
        EXPECT_EQ(e.where(), "line " + std::to_string(c.line)) << c.name << ": " << e.what();
        EXPECT_EQ(e.file(), folder.path() / "scene.xml") << c.name;
      }
    }
  }
}

// Export, then import: the same scene up to the camera's look_at point (a point on the same ray) and the
// names Mitsuba cannot carry (emissive materials take their emitter into the name).
void expect_round_trip(const Scene& original, const TempFolder& folder) {
  const std::filesystem::path xml = export_mitsuba_scene(original, folder.path() / "export");
  const Scene back = load_scene(xml);
  EXPECT_EQ(back.camera.position, original.camera.position);
  EXPECT_NEAR(glm::length(glm::normalize(back.camera.look_at - back.camera.position) -
                          glm::normalize(original.camera.look_at - original.camera.position)), 0.0f, 1e-6f);
  EXPECT_NEAR(back.camera.vfov_deg, original.camera.vfov_deg, 1e-5f);
  EXPECT_EQ(back.camera.width, original.camera.width);
  EXPECT_EQ(back.camera.height, original.camera.height);
  EXPECT_EQ(back.render.spp, original.render.spp);
  EXPECT_EQ(back.render.max_depth, original.render.max_depth);
  EXPECT_EQ(back.render.rr_depth, original.render.rr_depth);
  ASSERT_EQ(back.shapes.size(), original.shapes.size());
  for (std::uint32_t id = 0; id < original.shapes.size(); ++id) {
    const Material &a = original.material_of(id), &b = back.material_of(id);
    EXPECT_EQ(b.type, a.type) << id;
    if (a.type == MaterialType::Diffuse || a.type == MaterialType::Emissive) { EXPECT_EQ(b.albedo, a.albedo) << id; }
    if (a.type == MaterialType::Mirror) { EXPECT_EQ(b.reflectance, a.reflectance) << id; }
    if (a.type == MaterialType::Glass) { EXPECT_EQ(b.ior, a.ior) << id; }
    if (a.type == MaterialType::Emissive) { EXPECT_EQ(b.radiance, a.radiance) << id; }
    if (a.type != MaterialType::Glass) { EXPECT_EQ(b.two_sided, a.two_sided) << id; }
    if (a.type != MaterialType::Emissive) { EXPECT_EQ(b.name, a.name) << id; }
    // Mitsuba's ids are global: a shape named like a material gets its geometry id appended.
    EXPECT_TRUE(back.shapes[id].name == original.shapes[id].name ||
                back.shapes[id].name == original.shapes[id].name + "-" + std::to_string(id))
        << back.shapes[id].name;
  }
  ASSERT_EQ(back.geometry.meshes.size(), original.geometry.meshes.size());
  for (std::size_t i = 0; i < original.geometry.meshes.size(); ++i) {
    EXPECT_EQ(back.geometry.meshes[i].geom_id, original.geometry.meshes[i].geom_id);
    EXPECT_EQ(back.geometry.meshes[i].positions, original.geometry.meshes[i].positions);
    EXPECT_EQ(back.geometry.meshes[i].indices, original.geometry.meshes[i].indices);
  }
  ASSERT_EQ(back.geometry.spheres.size(), original.geometry.spheres.size());
  for (std::size_t i = 0; i < original.geometry.spheres.size(); ++i) {
    EXPECT_EQ(back.geometry.spheres[i].geom_id, original.geometry.spheres[i].geom_id);
    EXPECT_EQ(back.geometry.spheres[i].center, original.geometry.spheres[i].center);
    EXPECT_EQ(back.geometry.spheres[i].radius, original.geometry.spheres[i].radius);
  }
  EXPECT_EQ(back.environment.type, original.environment.type);
  EXPECT_EQ(back.environment.radiance, original.environment.radiance);
  EXPECT_EQ(back.environment.scale, original.environment.scale);
  EXPECT_NEAR(back.environment.rotation_deg, original.environment.rotation_deg, 1e-4f);
  if (original.environment.type == EnvironmentType::Image) {
    EXPECT_EQ(back.environment.filter, EnvironmentFilter::Bilinear);
  }
}

TEST(MitsubaExport, RoundTripOfTheBundledScenes) {
  for (const char* name : {"cornell-box.json", "cornell-mirror-glass.json", "spheres.json", "white-furnace.json"}) {
    SCOPED_TRACE(name);
    TempFolder folder;
    Scene scene = load_scene(std::filesystem::path(TWINRAY_SOURCE_DIR) / "scenes" / name);
    scene.render.rr_depth = 4;
    scene.render.max_depth = 9;
    expect_round_trip(scene, folder);
  }
}

TEST(MitsubaExport, RoundTripOfOneSidedMaterialsAndARotatedMap) {
  TempFolder folder;
  Scene scene = empty_scene({1, 2, 3}, {0, 0, 0}, {0, 1, 0}, 50.0f, 20, 10);
  Material one_sided = diffuse(glm::vec3(0.3f));
  one_sided.name = "one sided";
  one_sided.two_sided = false;
  add_quad(scene, {0, 0, 0}, {1, 0, 0}, {0, 0, 1}, add_material(scene, one_sided));
  Material lamp = emissive(glm::vec3(5), glm::vec3(0.2f));
  lamp.name = "lamp";
  add_quad(scene, {0, 2, 0}, {0, 0, 1}, {1, 0, 0}, add_material(scene, lamp));
  Material chrome = mirror(glm::vec3(0.7f));
  chrome.name = "chrome";
  chrome.two_sided = false;
  add_sphere(scene, {0, 1, 0}, 0.25f, add_material(scene, chrome));
  write_exr(folder.path() / "sky.exr", Image(8, 4, 3));
  scene.environment.type = EnvironmentType::Image;
  scene.environment.image = folder.path() / "sky.exr";
  scene.environment.rotation_deg = -75.0f;
  scene.environment.scale = 0.5f;
  expect_round_trip(scene, folder);
}

// compare's export: a nearest-texel map goes to Mitsuba with every texel repeated k x k times, a bilinear
// one as it is (both renderers then look it up the same way), under its own name.
TEST(MitsubaExport, BilinearMapsAreWrittenAsTheyAreAndNearestOnesUpsampled) {
  TempFolder folder;
  Image map(6, 3, 3);
  for (std::size_t i = 0; i < map.data.size(); ++i) map.data[i] = static_cast<float>(i % 7) + 0.5f;
  write_exr(folder.path() / "sky.exr", map);
  Scene scene;
  scene.environment.type = EnvironmentType::Image;
  scene.environment.image = folder.path() / "sky.exr";
  MitsubaExportOptions options;
  options.env_upsample = 4;

  scene.environment.filter = EnvironmentFilter::Nearest;
  export_mitsuba_scene(scene, folder.path() / "nearest", options);
  const Image upsampled = read_image(folder.path() / "nearest" / "textures" / "sky.exr");
  EXPECT_EQ(upsampled.width, 24);
  EXPECT_EQ(upsampled.height, 12);
  EXPECT_EQ(upsampled.at(7, 5, 1), map.at(1, 1, 1));

  scene.environment.filter = EnvironmentFilter::Bilinear;
  export_mitsuba_scene(scene, folder.path() / "bilinear", options);
  const Image copied = read_image(folder.path() / "bilinear" / "textures" / "sky.exr");
  ASSERT_EQ(copied.width, 6);
  ASSERT_EQ(copied.height, 3);
  EXPECT_EQ(copied.data, map.data);
}

// The shared Cornell box XML: the same scene as scenes/cornell-box-reference.json, and it renders to the
// Mitsuba reference.
TEST(MitsubaImport, SharedCornellBoxXmlRendersToTheReference) {
  const char* shared = std::getenv("TWINRAY_SHARED");
  if (shared == nullptr || *shared == '\0') GTEST_SKIP() << "TWINRAY_SHARED is not set: references/cornell-box/scene.xml not read";
  const std::filesystem::path dir = std::filesystem::path(shared) / "references" / "cornell-box";
  if (!std::filesystem::exists(dir / "scene.xml")) GTEST_SKIP() << dir / "scene.xml" << " does not exist";
  const Scene xml = load_scene(dir / "scene.xml");
  const Scene json = load_scene(std::filesystem::path(TWINRAY_SOURCE_DIR) / "scenes/cornell-box-reference.json");
  EXPECT_EQ(xml.render.spp, 4096);  // the XML's default parameter
  EXPECT_EQ(xml.camera.width, json.camera.width);
  EXPECT_NEAR(xml.camera.vfov_deg, json.camera.vfov_deg, 1e-4f);
  EXPECT_EQ(xml.camera.position, json.camera.position);
  EXPECT_EQ(xml.geometry.triangle_count(), json.geometry.triangle_count());
  EXPECT_EQ(xml.geometry.bounds().lo, json.geometry.bounds().lo);
  EXPECT_EQ(xml.geometry.bounds().hi, json.geometry.bounds().hi);

  Image reference = read_image(dir / "mitsuba_ref.exr");
  RenderOptions o;
  o.spp = 16;
  o.seed = 3;
  const Rendered r = render_scene(xml, o);
  const glm::dvec3 mean = image_mean(r.mean), ref = image_mean(reference);
  for (int c = 0; c < 3; ++c) EXPECT_NEAR(mean[c], ref[c], 0.01 * ref[c]) << "channel " << c;
}

// twinray compare against Mitsuba itself: needs the Mitsuba environment (not in CI: see docs/mitsuba.md).
TEST(MitsubaPeer, CompareAgreesOnTheCornellBoxAndFindsAChangedScene) {
  std::string why;
  if (!compare::probe_mitsuba(&why)) GTEST_SKIP() << why;
  TempFolder folder;
  Scene scene = load_scene(std::filesystem::path(TWINRAY_SOURCE_DIR) / "scenes/cornell-box-reference.json");
  scene.camera.width = scene.camera.height = 64;
  compare::CompareSettings s;
  s.spp = 64;
  s.batches = 8;
  s.threads = 2;
  s.out = folder.path() / "same";
  const compare::CompareResult same = compare::run_compare(scene, "cornell", s, [](const std::string&) {});
  EXPECT_TRUE(same.comparison.agree) << "largest |z| " << same.comparison.max_abs_z;
  EXPECT_EQ(same.json["verdict"], "agree");
  EXPECT_TRUE(std::filesystem::exists(s.out / "difference.png"));
  // Mitsuba renders the scene with a light 10% brighter: the verdict must say they differ.
  Scene brighter = scene;
  for (Material& m : brighter.materials)
    if (m.type == MaterialType::Emissive) m.radiance *= 1.1f;
  brighter.render.spp = s.spp / s.batches;
  compare::MitsubaRenderRequest request;
  request.scene_xml = export_mitsuba_scene(brighter, folder.path() / "brighter");
  request.out_exr = folder.path() / "brighter.exr";
  request.spp = s.spp / s.batches;
  request.batches = s.batches;
  request.threads = 2;
  const compare::MitsubaRender peer = compare::render_with_mitsuba(compare::find_mitsuba(), request);
  const compare::Comparison c = compare::compare_images(same.twinray.image, peer.image);
  EXPECT_FALSE(c.agree);
  EXPECT_GT(c.differing.size(), 10u);
}

}  // namespace
}  // namespace twinray

namespace twinray {
namespace {

// converge --peer mitsuba: Mitsuba's error-against-time series at doubling sample counts.
TEST(MitsubaPeer, ConvergeSeriesHasDoublingPoints) {
  std::string why;
  if (!compare::probe_mitsuba(&why)) GTEST_SKIP() << why;
  TempFolder folder;
  Scene scene = load_scene(std::filesystem::path(TWINRAY_SOURCE_DIR) / "scenes/cornell-box-reference.json");
  scene.camera.width = scene.camera.height = 32;
  RenderOptions o;
  o.spp = 64;
  const Image reference = render_scene(scene, o).mean;
  converge::StudySettings settings;
  settings.budget_seconds = 0.5;
  settings.max_spp = 8;
  const converge::ConvergeSeries s =
      converge::mitsuba_series(scene, reference, settings, folder.path() / "mitsuba", 2, [](const std::string&) {});
  EXPECT_EQ(s.backend, "mitsuba");
  ASSERT_GE(s.points.size(), 2u);
  for (std::size_t i = 0; i < s.points.size(); ++i) EXPECT_EQ(s.points[i].spp, 1 << i);
  // More samples, less error (each point halves the variance; 1 -> 2 spp can only fail by chance at 32x32).
  EXPECT_LT(s.points.back().error.rel_mse, s.points.front().error.rel_mse);
}

}  // namespace
}  // namespace twinray
