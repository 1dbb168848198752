// The shot spec: defaults, every class of bad input, sections that turn features off, path
// resolution, slices, and the shipped shots (docs/architecture.md §10 and §4). Shots are inline
// raw-string JSON.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>

#include "pipeline/shot/shot.h"
#include "sim/core/error.h"
#include "sim/core/log.h"
#include "tolerance.h"

namespace mudcrack {
namespace {

namespace fs = std::filesystem;

// the smallest valid shot: every other key takes its default
const char* kMinimal = R"({
  "mudcrack": 1,  // format version
  "source": { "type": "box" },
  "material": {}
})";

// a shot with every section on
const char* kFull = R"({
  "mudcrack": 1,
  "name": "full",
  "source": { "type": "box", "box": { "min": [0, 0, 0], "max": [0.5, 0.1, 0.5], "spacing": 0.02 } },
  "material": { "density": 1, "youngs_modulus": 2000, "poisson_ratio": 0.35 },
  "plasticity": { "alpha0": -0.04, "beta": 1, "xi": 1, "M": 1.87 },
  "moisture": { "eta": 0.4, "k_r": 1, "eps": 1, "D": 0.01, "lambda": 0.1 },
  "sim": { "h": 0.04 },
  "frames": { "start": 1, "end": 48, "fps": 24 },
  "colliders": { "ground": { "height": 0 } },
  "surfacing": { "zeta": 2 },
  "render": { "resolution": [640, 360], "camera": { "fov": 40 }, "turntable": { "views": 24 } }
})";

// fails a test on any warning it did not ask for (MuJoCo's MujocoTest)
class ShotTest : public ::testing::Test {
protected:
    void SetUp() override {
        log::reset_warnings();
        log::set_level(log::Level::Error);
    }
    void TearDown() override { EXPECT_EQ(log::warning_count(), m_expected_warnings); }
    int m_expected_warnings = 0;
};

// the InputError message of parsing `text`, or "" if it parsed
std::string error_of(const std::string& text, const std::string& path = "shots/t.json") {
    try {
        parse_shot(text, path);
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

void expect_contains(const std::string& message, std::initializer_list<const char*> parts) {
    for (const char* part : parts)
        EXPECT_NE(message.find(part), std::string::npos) << "missing \"" << part << "\" in:\n"
                                                         << message;
}

int line_count(const std::string& s) {
    if (s.empty()) return 0;
    int n = 1;
    for (char c : s) n += c == '\n';
    return n;
}

TEST_F(ShotTest, DefaultsFillEveryKeyOfPresentSections) {
    const Shot shot = parse_shot(kMinimal, "shots/minimal.json");
    EXPECT_EQ(shot.name, "minimal");
    EXPECT_EQ(shot.init.type, SourceType::Box);
    EXPECT_EQ(shot.init.box.spacing, 0.025);
    EXPECT_EQ(shot.init.box.max, Vec3(0.5, 0.1, 0.5));
    EXPECT_EQ(shot.init.seed, 1u);
    EXPECT_EQ(shot.sim.h, 0.05);
    EXPECT_EQ(shot.sim.elastic.youngs_modulus, 2000);
    EXPECT_EQ(shot.sim.elastic.poisson_ratio, 0.35);
    EXPECT_EQ(shot.sim.elastic.density, 1);
    EXPECT_EQ(shot.sim.time.dt_max, 1e-3);
    EXPECT_EQ(shot.sim.time.dt_fixed, 0);
    EXPECT_EQ(shot.sim.time.cfl_elastic, 0.5);
    EXPECT_EQ(shot.sim.time.frame_start, 1);
    EXPECT_EQ(shot.sim.time.frame_end, 24);
    EXPECT_EQ(shot.sim.gravity, Vec3(0, -9.81, 0));
    EXPECT_EQ(shot.sim.checkpoint_every, 10);
    EXPECT_EQ(shot.sim.grid_shift_interval, 0);  // a fixed grid
    EXPECT_EQ(shot.sim.grid_turn_interval, 0);   // along the world's axes
    EXPECT_EQ(shot.sim.precision, StatePrecision::Double);
    // the slice records the defaults it ran with
    expect_contains(shot.slice(Stage::Sim), {"\"youngs_modulus\": 2000.0", "\"dt_max\": 0.001"});
}

TEST_F(ShotTest, OmittedSectionsTurnFeaturesOff) {
    const Shot shot = parse_shot(kMinimal, "shots/minimal.json");
    EXPECT_FALSE(shot.sim.nacc.has_value());
    EXPECT_FALSE(shot.sim.moisture.has_value());
    EXPECT_FALSE(shot.sim.ground.has_value());
    EXPECT_TRUE(shot.sim.domain.is_auto);
    EXPECT_FALSE(shot.surface.has_value());
    EXPECT_FALSE(shot.render.has_value());
    // with nothing downstream, the caches carry velocity only
    EXPECT_TRUE(shot.sim.cache.velocity);
    EXPECT_FALSE(shot.sim.cache.theta || shot.sim.cache.saturation || shot.sim.cache.alpha ||
                 shot.sim.cache.Jw || shot.sim.cache.Fe);
    EXPECT_EQ(shot.slice(Stage::Sim).find("moisture"), std::string::npos);
}

TEST_F(ShotTest, PresentSectionsGetDefaultsAndDerivedValues) {
    const Shot shot = parse_shot(kFull, "shots/full.json");
    EXPECT_EQ(shot.name, "full");
    ASSERT_TRUE(shot.sim.nacc && shot.sim.moisture && shot.sim.ground && shot.surface &&
                shot.render);
    // beta is shorthand for beta0 = beta1 (docs/physics.md §4.8 T21)
    EXPECT_EQ(shot.sim.nacc->beta0, 1);
    EXPECT_EQ(shot.sim.nacc->beta1, 1);
    EXPECT_EQ(shot.sim.nacc->alpha0, -0.04);
    EXPECT_TRUE(shot.sim.nacc->hardening);
    // particles start saturated: theta_init = eta
    EXPECT_EQ(shot.sim.moisture->theta_init, 0.4);
    EXPECT_EQ(shot.sim.moisture->cg_max_iterations, 50);
    EXPECT_EQ(shot.sim.ground->mode, ColliderMode::Sticky);
    EXPECT_EQ(shot.surface->mode, SurfaceMode::Ours);
    EXPECT_EQ(shot.surface->format, "glb");
    EXPECT_EQ(shot.render->width, 640);
    EXPECT_EQ(shot.render->height, 360);
    EXPECT_FALSE(shot.render->camera.is_auto);
    EXPECT_EQ(shot.render->camera.fov_deg, 40);
    EXPECT_EQ(shot.render->camera.position, Vec3(3, 2, 3));
    EXPECT_TRUE(shot.render->turntable);
    EXPECT_EQ(shot.render->turntable_views, 24);
    EXPECT_EQ(shot.render->turntable_frame, -1);
    // surfacing with moisture and plasticity needs every attribute
    const CacheAttributes& c = shot.sim.cache;
    EXPECT_TRUE(c.velocity && c.theta && c.saturation && c.alpha && c.Jw && c.Fe);
    expect_contains(shot.slice(Stage::Sim),
                    {"\"beta0\": 1.0", "\"theta_init\": 0.4", "\"Jw\": true"});
    EXPECT_EQ(shot.slice(Stage::Sim).find("\"beta\":"), std::string::npos);
}

TEST_F(ShotTest, RenderWithoutTurntableOrCameraSections) {
    const Shot shot = parse_shot(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "plasticity": {}, "render": {"color_mode": "hardening"}})",
                                 "t.json");
    ASSERT_TRUE(shot.render);
    EXPECT_TRUE(shot.render->camera.is_auto);
    EXPECT_FALSE(shot.render->turntable);
    EXPECT_EQ(shot.render->color_mode, ColorMode::Hardening);
    // the cache holds the physics' state: alpha (plasticity); no moisture, so no theta/saturation;
    // no surfacing, so no Fe
    EXPECT_TRUE(shot.sim.cache.alpha);
    EXPECT_FALSE(shot.sim.cache.saturation || shot.sim.cache.theta || shot.sim.cache.Jw ||
                 shot.sim.cache.Fe);
}

// A render key never re-simulates: in a shot with moisture and no surfacing, the color mode (which
// decides whether the render draws saturation) leaves the sim slice as it is, so `make` re-runs
// only the render
TEST_F(ShotTest, RenderColorModeLeavesTheSimSliceOfAShotWithoutSurfacing) {
    const std::string base = R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "plasticity": {}, "moisture": {}, "render": {"color_mode": "MODE"}})";
    std::string sim_slice;
    for (const char* mode : {"plain", "moisture", "hardening"}) {
        std::string text = base;
        text.replace(text.find("MODE"), 4, mode);
        const Shot shot = parse_shot(text, "t.json");
        EXPECT_TRUE(shot.sim.cache.saturation && shot.sim.cache.alpha && shot.sim.cache.theta)
            << mode;
        EXPECT_FALSE(shot.sim.cache.Fe) << mode;
        if (sim_slice.empty()) sim_slice = shot.slice(Stage::Sim);
        EXPECT_EQ(shot.slice(Stage::Sim), sim_slice) << mode;
    }
}

// An on-request attribute (MC_CACHED_ATTRIBUTES' OnRequest policy: the damage) is cached only when
// asked for, and asking changes only that shot's sim slice; asking without its physics is refused.
TEST_F(ShotTest, OnRequestAttributeIsCachedOnlyWhenAskedAndNeedsItsPhysics) {
    const std::string base = R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "plasticity": {"damage_strain": 0.01}, "moisture": {}SIM})";
    auto with = [&](const std::string& sim) {
        std::string text = base;
        text.replace(text.find("SIM"), 3, sim);
        return text;
    };
    const Shot plain = parse_shot(with(""), "t.json");
    EXPECT_FALSE(plain.sim.cache.damage);
    EXPECT_EQ(plain.slice(Stage::Sim).find("damage\":"), std::string::npos)
        << plain.slice(Stage::Sim);
    const Shot asked = parse_shot(with(R"(, "sim": {"cache": {"damage": true}})"), "t.json");
    EXPECT_TRUE(asked.sim.cache.damage);
    EXPECT_NE(asked.slice(Stage::Sim), plain.slice(Stage::Sim));
    EXPECT_EQ(asked.slice(Stage::Init), plain.slice(Stage::Init));
    const Shot declined = parse_shot(with(R"(, "sim": {"cache": {"damage": false}})"), "t.json");
    EXPECT_FALSE(declined.sim.cache.damage);
    // no damage physics (no /plasticity/damage_strain): the request names the key and what it needs
    expect_contains(
        error_of(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {}, "plasticity": {},
        "sim": {"cache": {"damage": true}}})"),
        {"shots/t.json: /sim/cache/damage = true", "/plasticity/damage_strain"});
}

TEST_F(ShotTest, MalformedJsonNamesFileLineAndColumn) {
    const std::string msg =
        error_of("{\n  \"mudcrack\": 1,\n  \"source\": {\"type\": \"box\",}\n}", "shots/x.json");
    expect_contains(msg, {"shots/x.json:3:", "line 3", "malformed JSON"});
}

TEST_F(ShotTest, DuplicateKeysNameFilePointerAndBothValues) {
    const std::string msg = error_of(R"({"mudcrack": 1, "source": {"type": "box"},
        "material": {"density": 1, "youngs_modulus": 2000, "density": 5},
        "render": {"camera": {"fov": 40, "fov": 50}}})",
                                     "shots/dup.json");
    expect_contains(
        msg,
        {"shots/dup.json: /material/density = 5: duplicate key: the same object sets it earlier to 1",
         "shots/dup.json: /render/camera/fov = 50: duplicate key: the same object sets it earlier to 40"});
    EXPECT_EQ(line_count(msg), 2) << msg;
    // a whole section written twice, and a key whose name needs escaping in a pointer
    expect_contains(
        error_of(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "sim": {"h": 0.04}, "sim": {"h": 0.02}})"),
        {"/sim = {\"h\":0.02}: duplicate key: the same object sets it earlier to {\"h\":0.04}"});
    expect_contains(
        error_of(
            R"({"mudcrack": 1, "source": {"type": "box"}, "material": {}, "a/b": 1, "a/b": 2})"),
        {"/a~1b = 2: duplicate key: the same object sets it earlier to 1"});
    // the same key in different objects is no duplicate; comments are still allowed
    EXPECT_EQ(
        error_of(R"({"mudcrack": 1, "source": {"type": "box", "box": {"min": [0, 0, 0]}}, /* note */
        "material": {}, "colliders": {"domain": {"min": [-1, -1, -1]}}})"),
        "");
}

TEST_F(ShotTest, MissingVersionIsAnError) {
    expect_contains(error_of(R"({"source": {"type": "box"}, "material": {}})"),
                    {"shots/t.json: /mudcrack = (missing): required"});
}

TEST_F(ShotTest, OtherMajorVersionIsAnError) {
    expect_contains(error_of(R"({"mudcrack": 2, "source": {"type": "box"}, "material": {}})"),
                    {"shots/t.json: /mudcrack = 2:", "this build reads 1"});
}

TEST_F(ShotTest, VersionMustBeTheInteger1) {
    expect_contains(error_of(R"({"mudcrack": 2.0, "source": {"type": "box"}, "material": {}})"),
                    {"/mudcrack = 2.0: unsupported"});
    expect_contains(error_of(R"({"mudcrack": "1", "source": {"type": "box"}, "material": {}})"),
                    {"/mudcrack = \"1\": must be an integer"});
    EXPECT_EQ(
        parse_shot(R"({"mudcrack": 1.0, "source": {"type": "box"}, "material": {}})", "t.json")
            .sim.h,
        0.05);
    expect_contains(error_of("[1, 2]"), {"shots/t.json:  = [1,2]: a shot must be a JSON object"});
}

TEST_F(ShotTest, HeightfieldAndImagePaths) {
    const Shot shot = parse_shot(R"({"mudcrack": 1, "material": {},
        "source": {"type": "heightfield", "heightfield": {"size": [2, 3], "base": 0.4}}})",
                                 "t.json");
    EXPECT_EQ(shot.init.type, SourceType::Heightfield);
    EXPECT_EQ(shot.init.heightfield.size, Vec3(2, 0, 3));
    EXPECT_EQ(shot.init.heightfield.base, 0.4);
    EXPECT_TRUE(shot.init.heightfield.image.empty());
    const std::string msg = error_of(R"({"mudcrack": 1, "material": {},
        "source": {"type": "heightfield", "heightfield": {"base": 0.1, "channel_depth": 0.2, "image": "h.png"}}})",
                                     "/tmp/mudcrack_none/t.json");
    expect_contains(
        msg,
        {"/source/heightfield/image = \"h.png\": file not found (looked for /tmp/mudcrack_none/h.png"});
}

TEST_F(ShotTest, UnknownKeysSuggestTheNearestKey) {
    const std::string msg = error_of(R"({"mudcrack": 1, "source": {"type": "box"},
        "material": {"youngs_modulis": 3}, "sim": {"fps": 24}, "grund": {}})");
    expect_contains(
        msg, {"/material/youngs_modulis = 3: unknown key (did you mean /material/youngs_modulus?)",
              "/sim/fps = 24: unknown key (did you mean /frames/fps?)",
              "/grund = {}: unknown key (did you mean /colliders/ground?)"});
}

TEST_F(ShotTest, EllipseFootprintTakesEveryLattice) {
    for (const char* lattice : {"regular", "jittered", "mesh"}) {
        const std::string box =
            R"({"lattice": ")" + std::string(lattice) + R"(", "footprint": "ellipse"})";
        const Shot shot = parse_shot(
            R"({"mudcrack": 1, "source": {"type": "box", "box": )" + box + R"(}, "material": {}})",
            "t.json");
        EXPECT_EQ(shot.init.box.footprint, Footprint::Ellipse) << lattice;
    }
}

TEST_F(ShotTest, StrengthFieldAzimuthsAreEvenUnlessAShotKeepsRandom) {
    const auto field = [](const std::string& keys) {
        return R"({"mudcrack": 1, "source": {"type": "box"}, "material": {}, "plasticity": {},
            "init": {"strength_field": {)" +
               keys + "}}}";
    };
    const Shot fresh = parse_shot(field(""), "t.json");
    ASSERT_TRUE(fresh.init.strength_field);
    EXPECT_EQ(fresh.init.strength_field->azimuths, ModeAzimuths::Even);
    const Shot kept = parse_shot(field(R"("azimuths": "random")"), "t.json");
    EXPECT_EQ(kept.init.strength_field->azimuths, ModeAzimuths::Random);
    expect_contains(error_of(field(R"("azimuths": "spiral")"), "shots/mud.json"),
                    {"shots/mud.json: /init/strength_field/azimuths = \"spiral\""});
}

TEST_F(ShotTest, GridTurnAnglesAreGoldenUnlessAShotKeepsRandom) {
    const auto turned = [](const std::string& keys) {
        return R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
            "sim": {"grid_turn": 5)" +
               keys + "}}";
    };
    EXPECT_EQ(parse_shot(turned(""), "t.json").sim.grid_turn_angles, SimModel::TurnAngles::Golden);
    EXPECT_EQ(
        parse_shot(turned(R"(, "grid_turn_angles": "random")"), "t.json").sim.grid_turn_angles,
        SimModel::TurnAngles::Random);
    expect_contains(error_of(turned(R"(, "grid_turn_angles": "spiral")"), "shots/mud.json"),
                    {"shots/mud.json: /sim/grid_turn_angles = \"spiral\""});
}

TEST_F(ShotTest, WrongTypesAreErrors) {
    const std::string msg =
        error_of(R"({"mudcrack": 1, "source": {"type": "box", "box": {"min": [0, 0]}},
        "material": {"density": "heavy"}, "frames": {"end": 2.5}, "surfacing": {"cracks": 1},
        "sim": []})");
    expect_contains(msg, {"/material/density = \"heavy\": must be a number [kg/m^3]",
                          "/frames/end = 2.5: must be an integer",
                          "/surfacing/cracks = 1: must be true or false",
                          "/source/box/min = [0,0]: must be an array [x, y, z] of 3 numbers [m]",
                          "/sim = []: must be an object"});
    EXPECT_EQ(line_count(msg), 5) << msg;
}

TEST_F(ShotTest, OutOfRangeNamesPointerValueAndUnits) {
    const std::string msg = error_of(R"({"mudcrack": 1, "source": {"type": "box"},
        "material": {"youngs_modulus": -300000}})",
                                     "shots/riverbed.json");
    EXPECT_EQ(msg, "shots/riverbed.json: /material/youngs_modulus = -300000: must be > 0 [Pa]");
    expect_contains(
        error_of(
            R"({"mudcrack": 1, "source": {"type": "box"}, "material": {"poisson_ratio": 0.5}})"),
        {"/material/poisson_ratio = 0.5: must be in (-1, 0.5)"});
    expect_contains(error_of(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "render": {"resolution": [8, 360]}})"),
                    {"/render/resolution/0 = 8: must be in [16, 16384] [px]"});
    // the renderer's own limit is checked here, at the shot, where the file can be named
    expect_contains(error_of(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "render": {"resolution": [960, 16385]}})",
                             "shots/huge.json"),
                    {"shots/huge.json: /render/resolution/1 = 16385: must be in [16, 16384] [px]"});
    expect_contains(error_of(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "sim": {"grid_shift": -200}})"),
                    {"/sim/grid_shift = -200: must be >= 0 [steps]"});
    const Shot moving = parse_shot(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "sim": {"grid_shift": 200}})",
                                   "t.json");
    EXPECT_EQ(moving.sim.grid_shift_interval, 200);
    // the state's precision: "double" or "float", nothing else
    EXPECT_EQ(parse_shot(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "sim": {"precision": "float"}})",
                         "t.json")
                  .sim.precision,
              StatePrecision::Float);
    expect_contains(error_of(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "sim": {"precision": "half"}})",
                             "shots/half.json"),
                    {"shots/half.json: /sim/precision = \"half\": must be one of \"double\", "
                     "\"float\""});
    // a turned grid: every k steps, an auto domain (its walls turn), a vertical gravity
    expect_contains(error_of(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "sim": {"grid_turn": -20}})"),
                    {"/sim/grid_turn = -20: must be >= 0 [steps]"});
    expect_contains(
        error_of(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "sim": {"grid_turn": 20},
        "colliders": {"domain": {"min": [-2, -2, -2], "max": [2, 2, 2]}}})",
                 "shots/walled.json"),
        {"shots/walled.json: /sim/grid_turn = 20: needs the domain derived from the "
         "particles (the domain's walls turn with the grid): leave /colliders/domain out"});
    expect_contains(error_of(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "sim": {"grid_turn": 20, "gravity": [1, -9.81, 0]}})"),
                    {"/sim/grid_turn = 20: needs a vertical /sim/gravity (the grid turns about the "
                     "vertical), not [1,-9.81,0]"});
    const Shot turned = parse_shot(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "sim": {"grid_turn": 20, "gravity": [0, -3.7, 0]}})",
                                   "t.json");
    EXPECT_EQ(turned.sim.grid_turn_interval, 20);
}

TEST_F(ShotTest, EnumTypoSuggestsTheChoice) {
    const std::string msg = error_of(R"({"mudcrack": 1, "source": {"type": "bx"}, "material": {},
        "colliders": {"ground": {"mode": "stiky"}}})");
    expect_contains(
        msg,
        {"/source/type = \"bx\": must be one of \"mesh\", \"box\", \"heightfield\" (did you mean \"box\"?)",
         "/colliders/ground/mode = \"stiky\": must be one of \"sticky\", \"slip\", \"separate\" "
         "(did you mean \"sticky\"?)"});
    // the bad required key is reported once, not again as missing
    EXPECT_EQ(line_count(msg), 2) << msg;
}

TEST_F(ShotTest, FbxIsRefusedWithTheReason) {
    expect_contains(error_of(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "surfacing": {"format": "fbx"}})"),
                    {"/surfacing/format = \"fbx\":", "4686", "glb"});
}

TEST_F(ShotTest, PlatesKeysAreBoundedAndDebrisNeedsThePlatesMode) {
    const Shot shot =
        parse_shot(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {}, "sim": {"h": 0.03},
        "surfacing": {"mode": "plates", "min_piece_size": 3, "debris": "points"}})",
                   "t.json");
    ASSERT_TRUE(shot.surface.has_value());
    EXPECT_EQ(shot.surface->mode, SurfaceMode::Plates);
    EXPECT_EQ(shot.surface->debris, DebrisOutput::Points);
    EXPECT_EQ(shot.surface->min_piece_size, 3);
    EXPECT_EQ(shot.surface->cell_size, 0.03);  // /sim/h: min_piece_size's unit
    const std::string msg = error_of(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "surfacing": {"mode": "ours", "debris": "points", "min_piece_size": 0, "debris_gap": 0,
                      "close_gaps": -1, "open_speed": -0.1, "wall_smoothing": 1000}})");
    expect_contains(msg, {"/surfacing/debris = \"points\": needs /surfacing/mode = \"plates\"",
                          "/surfacing/min_piece_size = 0: must be > 0",
                          "/surfacing/debris_gap = 0: must be > 0",
                          "/surfacing/close_gaps = -1: must be in [0, 1]",
                          "/surfacing/open_speed = -0.1: must be in [0, 10]",
                          "/surfacing/wall_smoothing = 1000: must be in [0, 100]"});
    expect_contains(error_of(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "surfacing": {"mode": "plate"}})"),
                    {"/surfacing/mode = \"plate\"", "(did you mean \"plates\"?)"});
}

TEST_F(ShotTest, FixedDtAboveTheElasticBoundIsRefused) {
    // c_p = sqrt(E (1-nu) / ((1+nu)(1-2nu) rho)) = 28.33 m/s; bound = 0.5 * 0.02 / c_p = 3.53e-4 s
    const char* shot = R"({"mudcrack": 1, "source": {"type": "box"},
        "material": {"youngs_modulus": 1000, "poisson_ratio": 0.35, "density": 2},
        "sim": {"h": 0.02, "dt": %s}})";
    char text[512];
    std::snprintf(text, sizeof text, shot, "1e-3");
    expect_contains(error_of(text),
                    {"/sim/dt = 0.001: exceeds the elastic bound C_E h / c_p = 0.000353 s",
                     "E=1000 Pa", "nu=0.35", "rho=2 kg/m^3", "h=0.02 m"});
    std::snprintf(text, sizeof text, shot, "3.5e-4");
    const Shot ok = parse_shot(text, "t.json");
    EXPECT_EQ(ok.sim.time.dt_fixed, 3.5e-4);
    EXPECT_LE(ok.sim.time.dt_fixed, elastic_dt_bound(ok.sim));
    EXPECT_NEAR(elastic_dt_bound(ok.sim), 0.5 * 0.02 / std::sqrt(1000 * 0.65 / (1.35 * 0.3 * 2)),
                tol::kRoundoff);
}

// a step mc-sim survives but that takes more than 10^4 substeps a frame is refused, naming the
// key that sets it, its value and the substeps (a Poisson ratio just under 0.5 gave 1e-8 s steps,
// hours of simulation with no word); the shipped shots take at most 405
TEST_F(ShotTest, StepsPastTenThousandSubstepsAFrameAreRefused) {
    const auto shot_with = [](const std::string& material, const std::string& more) {
        return R"({"mudcrack": 1, "source": {"type": "box"}, "material": {)" + material + "}" +
               more + "}";
    };
    // c_p = 56.7 m/s at nu = 0.35: 94 substeps a frame; at 0.4999999999, 3.0e6
    expect_contains(
        error_of(shot_with(R"("poisson_ratio": 0.4999999999)", "")),
        {"/material/poisson_ratio = 0.4999999999: gives a stable time step of 1.369e-08 s (the "
         "elastic bound C_E h / c_p (c_p = 1.826e+06 m/s, with /material/youngs_modulus = 2000.0 "
         "and /material/density = 1.0)): 3.043e+06 substeps per frame of 1 / fps = 0.04167 s; "
         "expected at most 1e+04"});
    expect_contains(error_of(shot_with(R"("youngs_modulus": 1e10)", "")),
                    {"/material/youngs_modulus = 10000000000.0: gives a stable time step",
                     "/material/poisson_ratio = 0.35 and /material/density = 1.0", "substeps"});
    expect_contains(error_of(shot_with("", R"(, "sim": {"dt_max": 1e-7})")),
                    {"/sim/dt_max = 1e-07: gives a stable time step of 1e-07 s (the largest step "
                     "/sim/dt_max): 4.167e+05 substeps per frame"});
    // frames of 1000 s (gravity over one of them sets the step): the step for frames of 1/24 s
    // would do
    expect_contains(error_of(shot_with("", R"(, "frames": {"fps": 0.001})")),
                    {"/frames/fps = 0.001: frames of 1000 s take 3.27e+08 substeps each",
                     "expected at most 1e+04: frames per second of simulated time"});
    // nu = 0.4999 (about 3,000) and every shipped shot pass
    EXPECT_NO_THROW(parse_shot(shot_with(R"("poisson_ratio": 0.4999)", ""), "t.json"));
}

TEST_F(ShotTest, CrossKeyChecks) {
    const std::string msg = error_of(R"({"mudcrack": 1,
        "source": {"type": "box", "box": {"min": [0, 0, 0], "max": [1, -0.1, 1]}},
        "material": {}, "frames": {"start": 10, "end": 5},
        "moisture": {"eta": 0.4, "theta_init": 0.5}})");
    expect_contains(
        msg, {"/source/box/max = [1,-0.1,1]: must be > /source/box/min = [0,0,0] on every axis [m]",
              "/frames/end = 5: must be >= /frames/start = 10",
              "/moisture/theta_init = 0.5: must be in [0, /moisture/eta = 0.4]"});
    EXPECT_EQ(line_count(msg), 3) << msg;
}

// The evaporation ramp is given in the shot's frames and kept as times (frame f ends at f / fps);
// a ramp whose full frame does not come after its start is refused by key and value.
TEST_F(ShotTest, EvaporationRampFramesBecomeTimes) {
    const Shot shot = parse_shot(R"({"mudcrack": 1,
        "source": {"type": "box", "box": {"min": [0, 0, 0], "max": [1, 0.1, 1]}},
        "material": {}, "frames": {"fps": 24},
        "moisture": {"evaporation_ramp": [6, 18]}})",
                                 "t.json");
    ASSERT_TRUE(shot.sim.moisture);
    EXPECT_DOUBLE_EQ(shot.sim.moisture->evaporation_ramp_start, 6.0 / 24);
    EXPECT_DOUBLE_EQ(shot.sim.moisture->evaporation_ramp_end, 18.0 / 24);
    const std::string msg = error_of(R"({"mudcrack": 1,
        "source": {"type": "box", "box": {"min": [0, 0, 0], "max": [1, 0.1, 1]}},
        "material": {}, "moisture": {"evaporation_ramp": [12, 12]}})");
    expect_contains(
        msg, {"/moisture/evaporation_ramp = [12,12]: must be [start, full] with full > start"});
    expect_contains(error_of(R"({"mudcrack": 1,
        "source": {"type": "box", "box": {"min": [0, 0, 0], "max": [1, 0.1, 1]}},
        "material": {}, "moisture": {"evaporation_ramp": [-1, 12]}})"),
                    {"/moisture/evaporation_ramp"});
}

// The diffusion operator is chosen by name; a name the solver does not know, or the grid operator
// with the implicit Robin term (a particle sum it has no pass for), is refused by key and value.
TEST_F(ShotTest, DiffusionOperatorIsChosenByNameAndRefusedWhereItCannotServe) {
    const std::string box = R"("source": {"type": "box", "box": {"min": [0, 0, 0],
        "max": [1, 0.1, 1]}}, "material": {})";
    const Shot shot = parse_shot(
        R"({"mudcrack": 1, )" + box + R"(, "moisture": {"diffusion_operator": "grid"}})", "t.json");
    ASSERT_TRUE(shot.sim.moisture);
    EXPECT_EQ(shot.sim.moisture->diffusion_operator, MoistureParams::DiffusionOperator::Grid);
    const Shot paper = parse_shot(R"({"mudcrack": 1, )" + box + R"(, "moisture": {}})", "t.json");
    EXPECT_EQ(paper.sim.moisture->diffusion_operator, MoistureParams::DiffusionOperator::Particles);
    expect_contains(
        error_of(R"({"mudcrack": 1, )" + box + R"(, "moisture": {"diffusion_operator": "fv"}})"),
        {"/moisture/diffusion_operator = \"fv\": must be one of \"particles\", \"grid\""});
    expect_contains(error_of(R"({"mudcrack": 1, )" + box +
                             R"(, "moisture": {"diffusion_operator": "grid",
                                 "implicit_robin": true}})"),
                    {"/moisture/implicit_robin = true: must be false with "
                     "/moisture/diffusion_operator = \"grid\""});
}

TEST_F(ShotTest, MissingMeshFileIsAnError) {
    const std::string msg =
        error_of(R"({"mudcrack": 1, "source": {"type": "mesh", "mesh": {"path": "assets/none.obj"}},
        "material": {}})",
                 "/tmp/mudcrack_no_such_dir/shot.json");
    expect_contains(
        msg,
        {"/tmp/mudcrack_no_such_dir/shot.json: /source/mesh/path = \"assets/none.obj\": file not found",
         "/tmp/mudcrack_no_such_dir/assets/none.obj"});
    expect_contains(error_of(R"({"mudcrack": 1, "source": {"type": "mesh"}, "material": {}})"),
                    {"/source/mesh/path = (missing): required when /source/type = \"mesh\""});
}

TEST_F(ShotTest, AllErrorsAreReportedAtOnce) {
    const std::string msg = error_of(R"({"mudcrack": 3, "source": {"type": "box"},
        "material": {"youngs_modulus": 0, "density": -1, "poisson_ratio": 0.7},
        "sim": {"h": 0, "cfl_elastic": 2}, "plasticity": {"M": -1}})");
    EXPECT_EQ(line_count(msg), 7) << msg;
    expect_contains(msg, {"/mudcrack = 3", "/material/youngs_modulus = 0", "/material/density = -1",
                          "/material/poisson_ratio = 0.7", "/sim/h = 0", "/sim/cfl_elastic = 2",
                          "/plasticity/M = -1"});
    // every line names the file
    size_t pos = 0;
    int n = 0;
    while ((pos = msg.find("shots/t.json: /", pos)) != std::string::npos) ++n, ++pos;
    EXPECT_EQ(n, 7);
}

TEST_F(ShotTest, PathsResolveRelativeToTheShotFile) {
    const fs::path dir = fs::temp_directory_path() / "mudcrack_shot_test_paths";
    fs::remove_all(dir);
    fs::create_directories(dir / "assets");
    std::ofstream(dir / "assets" / "slab.obj") << "v 0 0 0\n";
    std::ofstream(dir / "riverbed.json") << R"({"mudcrack": 1, "material": {},
        "source": {"type": "mesh", "mesh": {"path": "assets/slab.obj", "scale": 2}}})";
    const Shot shot = load_shot((dir / "riverbed.json").string());
    EXPECT_EQ(shot.init.type, SourceType::Mesh);
    EXPECT_EQ(fs::path(shot.init.mesh.path), (dir / "assets" / "slab.obj").lexically_normal());
    EXPECT_EQ(shot.init.mesh.scale, 2);
    EXPECT_EQ(shot.name, "riverbed");
    // the slice records the resolved path, and only the selected source's settings
    expect_contains(shot.slice(Stage::Init), {(dir / "assets" / "slab.obj").string().c_str()});
    EXPECT_EQ(shot.slice(Stage::Init).find("\"box\""), std::string::npos);
    fs::remove_all(dir);
}

TEST_F(ShotTest, RenderOnlyEditLeavesEarlierSlicesIdentical) {
    const Shot a = parse_shot(kFull, "shots/full.json");
    std::string edited = kFull;
    const std::string from = R"("resolution": [640, 360], "camera": { "fov": 40 })";
    edited.replace(edited.find(from), from.size(), R"("resolution": [1920, 1080], "samples": 8)");
    const Shot b = parse_shot(edited, "shots/full.json");
    EXPECT_EQ(a.slice(Stage::Init), b.slice(Stage::Init));
    EXPECT_EQ(a.slice(Stage::Sim), b.slice(Stage::Sim));
    EXPECT_EQ(a.slice(Stage::Surface), b.slice(Stage::Surface));
    EXPECT_EQ(a.slice_hash(Stage::Sim), b.slice_hash(Stage::Sim));
    EXPECT_NE(a.slice(Stage::Render), b.slice(Stage::Render));
    EXPECT_NE(a.slice_hash(Stage::Render), b.slice_hash(Stage::Render));
    EXPECT_EQ(a.slice_hash(Stage::Render).size(), 16u);
}

TEST_F(ShotTest, SlicesNestAndIgnoreSpelling) {
    const Shot a = parse_shot(kFull, "shots/full.json");
    // each slice holds the earlier stages' keys; /sim/h is the only sim key init reads
    expect_contains(a.slice(Stage::Init), {"\"h\": 0.04", "\"spacing\": 0.02"});
    EXPECT_EQ(a.slice(Stage::Init).find("youngs_modulus"), std::string::npos);
    EXPECT_EQ(a.slice(Stage::Sim).find("\"surfacing\""), std::string::npos);
    expect_contains(a.slice(Stage::Surface), {"\"surfacing\"", "\"youngs_modulus\""});
    EXPECT_EQ(a.slice(Stage::Surface).find("\"render\""), std::string::npos);
    // integer vs float spelling, comments, key order and the beta shorthand do not matter
    const Shot b = parse_shot(R"({
      "render": { "turntable": { "views": 24 }, "camera": { "fov": 40.0 }, "resolution": [640, 360] },
      "surfacing": { "zeta": 2.0 }, "colliders": { "ground": { "height": 0.0 } },
      "frames": { "fps": 24.0, "start": 1, "end": 48 }, "sim": { "h": 0.04 },
      "moisture": { "eta": 0.4, "k_r": 1.0, "eps": 1.0, "D": 0.01, "lambda": 0.1, "theta_init": 0.4 },
      // no shorthand
      "plasticity": { "alpha0": -0.04, "beta0": 1, "beta1": 1.0, "xi": 1, "M": 1.87 },
      "material": { "poisson_ratio": 0.35, "youngs_modulus": 2e3, "density": 1 },
      "source": { "box": { "spacing": 0.02, "min": [0, 0, 0], "max": [0.5, 0.1, 0.5] }, "type": "box" },
      "name": "renamed", "mudcrack": 1 })",
                              "elsewhere/full.json");
    for (Stage s : {Stage::Init, Stage::Sim, Stage::Surface, Stage::Render})
        EXPECT_EQ(a.slice(s), b.slice(s)) << stage_name(s);
}

TEST_F(ShotTest, LowZetaWarns) {
    parse_shot(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "moisture": {"eta": 0.5}, "surfacing": {"zeta": 1.5}})",
               "t.json");
    // (1 - 0.5)^(-2/3) = 1.587 > 1.5
    EXPECT_EQ(log::warning_count(), 1);
    parse_shot(R"({"mudcrack": 1, "source": {"type": "box"}, "material": {},
        "moisture": {"eta": 0.5}, "surfacing": {"zeta": 1.6}})",
               "t.json");
    EXPECT_EQ(log::warning_count(), 1);
    m_expected_warnings = 1;
}

TEST_F(ShotTest, SpecTableListsEveryKey) {
    const std::string table = spec_table_text();
    expect_contains(table, {"/material/youngs_modulus", "Pa", "/moisture/theta_init", "derived",
                            "/render/turntable/views", "enum(sticky|slip|separate)", "(-1, 0.5)"});
}

TEST_F(ShotTest, ShippedShotsValidate) {
    const std::string dir = std::string(MUDCRACK_SOURCE_DIR) + "/shots/";
    const Shot demo = load_shot(dir + "demo.json");
    EXPECT_TRUE(demo.sim.nacc && demo.sim.moisture && demo.surface && demo.render);
    // the round puddle demo.json's comments describe: Mesh_3 fills the ellipse inscribed in a
    // 0.9 x 0.05 x 0.9 m box at the edge length derived from h, on a grid turned every 5 steps
    EXPECT_LT((demo.init.box.max - demo.init.box.min - Vec3(0.9, 0.05, 0.9)).norm(),
              tol::kRoundoff);
    EXPECT_EQ(demo.init.box.lattice, Lattice::Mesh);
    EXPECT_EQ(demo.init.box.footprint, Footprint::Ellipse);
    EXPECT_EQ(demo.init.edge_length, 0);
    EXPECT_EQ(demo.sim.h, 0.02);
    EXPECT_EQ(demo.sim.grid_turn_interval, 5);

    for (const char* name : {"bench_nacc_cube.json", "bench_moisture_cube.json"}) {
        const Shot bench = load_shot(dir + name);
        const Vec3 e = bench.init.box.max - bench.init.box.min;
        for (int a = 0; a < 3; ++a)
            EXPECT_EQ(std::round(e[a] / bench.init.box.spacing) + 1, 50) << name;
        EXPECT_EQ(bench.sim.time.dt_fixed, 2e-4) << name;
        EXPECT_EQ(bench.sim.initial_velocity, Vec3(0, -2, 0)) << name;
        // one frame of 404 steps
        const Real steps = (bench.sim.time.frame_end - bench.sim.time.frame_start + 1) /
                           bench.sim.time.fps / bench.sim.time.dt_fixed;
        EXPECT_NEAR(steps, 404, tol::kRoundoffLoose) << name;
        ASSERT_TRUE(bench.sim.nacc) << name;
        EXPECT_NEAR(bench.sim.nacc->alpha0, std::log(0.99), tol::kRoundoff) << name;
        EXPECT_FALSE(bench.surface || bench.render) << name;
        EXPECT_EQ(bench.sim.moisture.has_value(), std::string(name) == "bench_moisture_cube.json");
    }
}

// every shot the project ships must load; the figure shots follow Table 1 (Tu et al. 2023)
TEST_F(ShotTest, EveryShippedShotLoads) {
    const std::filesystem::path dir = std::filesystem::path(MUDCRACK_SOURCE_DIR) / "shots";
    int count = 0;
    for (const auto& entry : std::filesystem::directory_iterator(dir)) {
        if (entry.path().extension() != ".json") continue;
        EXPECT_NO_THROW(load_shot(entry.path().string())) << entry.path();
        ++count;
    }
    EXPECT_GE(count, 3);
    // Table 1's Fig. 8 ablation: eta = 0 (a), eps = 0 (b), the full model (c)
    const Shot a = load_shot((dir / "fig8_a.json").string()),
               b = load_shot((dir / "fig8_b.json").string()),
               c = load_shot((dir / "fig8_c.json").string());
    ASSERT_TRUE(a.sim.moisture && b.sim.moisture && c.sim.moisture);
    EXPECT_EQ(a.sim.moisture->eta, 0);
    EXPECT_EQ(b.sim.moisture->eps, 0);
    EXPECT_EQ(c.sim.moisture->eta, 0.4);
    EXPECT_EQ(c.sim.moisture->eps, 1);
}

// A float twin (shots/*_float.json) is its shot with /sim/precision "float" and nothing else: the
// README's stills of the two compare float with double, so an edit to one must reach the other.
TEST(ShotFiles, FloatTwinsDifferFromTheirShotOnlyInPrecision) {
    const std::string shots = std::string(MUDCRACK_SOURCE_DIR) + "/shots/";
    for (const std::string base : {"demo", "fig7_mossy_ground"}) {
        SCOPED_TRACE(base);
        const Shot double_shot = load_shot(shots + base + ".json");
        const Shot float_shot = load_shot(shots + base + "_float.json");
        EXPECT_EQ(double_shot.sim.precision, StatePrecision::Double);
        EXPECT_EQ(float_shot.sim.precision, StatePrecision::Float);
        EXPECT_EQ(float_shot.slice(Stage::Init), double_shot.slice(Stage::Init));
        std::string twin = float_shot.slice(Stage::Render);
        const std::string key = R"("precision": "float")";
        const size_t at = twin.find(key);
        ASSERT_NE(at, std::string::npos) << twin;
        twin.replace(at, key.size(), R"("precision": "double")");
        EXPECT_EQ(twin, double_shot.slice(Stage::Render));
    }
}

}  // namespace
}  // namespace mudcrack
