// Bitmap textures (core/texture.h): lookups against hand-computed values on a 2x2 image, wrap
// modes outside [0, 1], sRGB decoding of 8-bit files, the cache, Props errors, the diffuse
// BSDF with a textured reflectance, the JSON loader's handling, and the uv orientation through
// the OBJ reader's v flip.
#include "core/bsdf.h"
#include "core/error.h"
#include "core/image_io.h"
#include "core/mesh.h"
#include "core/scene_loader.h"
#include "core/texture.h"
#include "test_util.h"
#include <OpenImageIO/imageio.h>
#include <filesystem>
#include <gtest/gtest.h>

using namespace lpt;
namespace fs = std::filesystem;

namespace {

const Eigen::Array3f kRed(1, 0, 0), kGreen(0, 1, 0), kBlue(0, 0, 1), kYellow(1, 1, 0);

/// A file path in the tests' temp folder (the folder write_temp_file creates).
std::string temp_path(const std::string& name) {
    return (fs::path(test::write_temp_file("texture-marker.txt", "")).parent_path() / name).string();
}

/// 2x2 float EXR: top row red, green; bottom row blue, yellow.
std::string write_quad_exr(const std::string& name = "quad.exr") {
    Image img;
    img.width = img.height = 2;
    img.channels = 3;
    for (const Eigen::Array3f& c : {kRed, kGreen, kBlue, kYellow}) img.data.insert(img.data.end(), {c[0], c[1], c[2]});
    std::string path = temp_path(name);
    write_exr(path, img);
    return path;
}

/// 8-bit PNG with `channels` channels (alpha stored unassociated, as files carry it).
std::string write_png8(const std::string& name, int w, int h, int channels, const std::vector<uint8_t>& data) {
    std::string path = temp_path(name);
    auto out = OIIO::ImageOutput::create(path);
    EXPECT_TRUE(out);
    OIIO::ImageSpec spec(w, h, channels, OIIO::TypeDesc::UINT8);
    spec.attribute("oiio:UnassociatedAlpha", 1);
    EXPECT_TRUE(out->open(path, spec) && out->write_image(OIIO::TypeDesc::UINT8, data.data()) && out->close())
        << out->geterror();
    return path;
}

void expect_rgb(const Eigen::Array3f& got, const Eigen::Array3f& want, float tol = 1e-6f) {
    EXPECT_LT((got - want).abs().maxCoeff(), tol) << got.transpose() << " vs " << want.transpose();
}

std::string error_of(const std::function<void()>& f) {
    try {
        f();
    } catch (const SceneError& e) {
        return e.what();
    }
    return "";
}
void expect_has(const std::string& err, const std::string& part) {
    EXPECT_NE(err.find(part), std::string::npos) << "'" << part << "' not in: " << err;
}

std::shared_ptr<Props> bitmap_props(const std::string& file, const std::string& filter = "",
                                    const std::string& wrap = "") {
    auto t = std::make_shared<Props>();
    t->type = "bitmap";
    t->values["filename"] = file;
    if (!filter.empty()) t->values["filter_type"] = filter;
    if (!wrap.empty()) t->values["wrap_mode"] = wrap;
    return t;
}

Texture load(const std::string& path, TextureFilter f, TextureWrap w) {
    return Texture::load_bitmap(path, false, f, w);
}

}  // namespace

TEST(Texture, BilinearMatchesHandComputedValues) {
    Texture t = load(write_quad_exr(), TextureFilter::Bilinear, TextureWrap::Repeat);
    ASSERT_EQ(t.bitmap()->width, 2);
    // Pixel centres at ((i + 0.5)/w, (j + 0.5)/h); v = 0 is the top row.
    expect_rgb(t.eval({0.25f, 0.25f}), kRed);
    expect_rgb(t.eval({0.75f, 0.25f}), kGreen);
    expect_rgb(t.eval({0.25f, 0.75f}), kBlue);
    expect_rgb(t.eval({0.75f, 0.75f}), kYellow);
    expect_rgb(t.eval({0.5f, 0.5f}), Eigen::Array3f(0.5f, 0.5f, 0.25f));
    expect_rgb(t.eval({0.375f, 0.25f}), Eigen::Array3f(0.75f, 0.25f, 0.f));
    // (0.4, 0.6): x = 0.3, y = 0.7 past the top-left centre.
    // top = 0.7 red + 0.3 green; bottom = 0.7 blue + 0.3 yellow; 0.3 top + 0.7 bottom.
    expect_rgb(t.eval({0.4f, 0.6f}), Eigen::Array3f(0.42f, 0.30f, 0.49f));
    expect_rgb(t.mean(), Eigen::Array3f(0.5f, 0.5f, 0.25f));
    EXPECT_FALSE(t.is_constant());
    Texture c(Eigen::Array3f(0.1f, 0.2f, 0.3f));
    expect_rgb(c.eval({0.9f, -3.f}), Eigen::Array3f(0.1f, 0.2f, 0.3f));
    expect_rgb(c.mean(), Eigen::Array3f(0.1f, 0.2f, 0.3f));
}

TEST(Texture, WrapModesOutsideTheUnitSquare) {
    std::string path = write_quad_exr();
    Texture rep = load(path, TextureFilter::Bilinear, TextureWrap::Repeat);
    Texture mir = load(path, TextureFilter::Bilinear, TextureWrap::Mirror);
    Texture cla = load(path, TextureFilter::Bilinear, TextureWrap::Clamp);
    // u = 0 lies halfway between pixel column 0 and column -1.
    expect_rgb(rep.eval({0.f, 0.25f}), Eigen::Array3f(0.5f, 0.5f, 0.f));  // -1 -> 1 (green)
    expect_rgb(mir.eval({0.f, 0.25f}), kRed);                             // -1 -> 0
    expect_rgb(cla.eval({0.f, 0.25f}), kRed);                             // -1 -> 0
    // u = 1.375: columns 2 and 3 with weights 0.75 / 0.25.
    expect_rgb(rep.eval({1.375f, 0.25f}), Eigen::Array3f(0.75f, 0.25f, 0.f));  // 2 -> 0, 3 -> 1
    expect_rgb(mir.eval({1.375f, 0.25f}), Eigen::Array3f(0.25f, 0.75f, 0.f));  // 2 -> 1, 3 -> 0
    expect_rgb(cla.eval({1.375f, 0.25f}), kGreen);                             // both -> 1
    // Negative coordinates.
    expect_rgb(rep.eval({-0.25f, 0.25f}), kGreen);
    expect_rgb(mir.eval({-0.25f, 0.25f}), kRed);
    expect_rgb(cla.eval({-0.25f, 0.25f}), kRed);
    expect_rgb(rep.eval({0.25f, -0.25f}), kBlue);
    expect_rgb(mir.eval({0.25f, -0.25f}), kRed);
    expect_rgb(rep.eval({0.75f, 3.75f}), kYellow);
    // Mirror period is two images: u in [1, 2] reads the image reversed, [2, 3] as is.
    expect_rgb(mir.eval({1.25f, 0.25f}), kGreen);
    expect_rgb(mir.eval({2.25f, 0.25f}), kRed);
    expect_rgb(cla.eval({7.f, 9.f}), kYellow);
}

TEST(Texture, NearestLookups) {
    std::string path = write_quad_exr();
    Texture rep = load(path, TextureFilter::Nearest, TextureWrap::Repeat);
    Texture mir = load(path, TextureFilter::Nearest, TextureWrap::Mirror);
    Texture cla = load(path, TextureFilter::Nearest, TextureWrap::Clamp);
    expect_rgb(rep.eval({0.49f, 0.49f}), kRed);
    expect_rgb(rep.eval({0.51f, 0.49f}), kGreen);
    expect_rgb(rep.eval({0.49f, 0.51f}), kBlue);
    expect_rgb(rep.eval({0.99f, 0.99f}), kYellow);
    expect_rgb(rep.eval({1.1f, 0.2f}), kRed);    // column 2 -> 0
    expect_rgb(mir.eval({1.1f, 0.2f}), kGreen);  // column 2 -> 1
    expect_rgb(cla.eval({1.1f, 0.2f}), kGreen);
    expect_rgb(rep.eval({-0.1f, 0.2f}), kGreen);  // column -1 -> 1
    expect_rgb(mir.eval({-0.1f, 0.2f}), kRed);
    expect_rgb(cla.eval({-0.1f, 0.2f}), kRed);
}

TEST(Texture, EightBitFilesAreSrgbUnlessRaw) {
    // One row: 128, then 0 / 255 / 64 per channel.
    std::string png = write_png8("srgb.png", 2, 1, 3, {128, 128, 128, 0, 255, 64});
    Texture t = Texture::load_bitmap(png, false, TextureFilter::Nearest);
    const float s128 = 0.2158605f, s64 = 0.05126947f;  // ((c/255 + 0.055)/1.055)^2.4
    expect_rgb(t.eval({0.25f, 0.5f}), Eigen::Array3f::Constant(s128));
    expect_rgb(t.eval({0.75f, 0.5f}), Eigen::Array3f(0.f, 1.f, s64));
    Texture raw = Texture::load_bitmap(png, true, TextureFilter::Nearest);
    expect_rgb(raw.eval({0.25f, 0.5f}), Eigen::Array3f::Constant(128.f / 255.f));
    expect_rgb(raw.eval({0.75f, 0.5f}), Eigen::Array3f(0.f, 1.f, 64.f / 255.f));

    // Grey broadcasts to RGB.
    Texture grey = Texture::load_bitmap(write_png8("grey.png", 1, 1, 1, {128}), false);
    expect_rgb(grey.eval({0.5f, 0.5f}), Eigen::Array3f::Constant(s128));
    // Alpha is dropped, not multiplied into the colour.
    Texture rgba = Texture::load_bitmap(write_png8("rgba.png", 1, 1, 4, {128, 64, 255, 51}), false);
    expect_rgb(rgba.eval({0.5f, 0.5f}), Eigen::Array3f(s128, s64, 1.f));
    // Float images are linear whatever `raw` says.
    Texture exr = Texture::load_bitmap(write_quad_exr(), false);
    expect_rgb(exr.eval({0.5f, 0.5f}), Eigen::Array3f(0.5f, 0.5f, 0.25f));
}

TEST(Texture, MissingOrBadFilesNameTheFile) {
    std::string missing = temp_path("no-such-texture.png");
    expect_has(error_of([&] { Texture::load_bitmap(missing); }), "no-such-texture.png");
    std::string junk = test::write_temp_file("junk.png", "this is not a png");
    expect_has(error_of([&] { Texture::load_bitmap(junk); }), "junk.png");

    Props owner;
    owner.type = "diffuse";
    owner.file = "scene.json";
    owner.where = "materials.wood";
    owner.values["reflectance"] = bitmap_props(missing);
    std::string err = error_of([&] { texture_from_props(owner, "reflectance", Eigen::Array3f::Zero()); });
    expect_has(err, "materials.wood.reflectance.filename");
    expect_has(err, "no-such-texture.png");

    // Through a scene file: the error also names the shapes that use the material.
    const std::string scene = test::write_temp_file("missing_tex.json", R"({"camera": {"fov": 40},
      "materials": {"wood": {"type": "diffuse", "reflectance": {"type": "bitmap", "filename": ")" +
                                                                            missing + R"("}}},
      "shapes": [{"id": "desk", "type": "rectangle", "material": "wood"}, {"id": "chair", "type": "rectangle", "material": "wood"}]})");
    err = error_of([&] { load_scene(scene); });
    expect_has(err, "missing_tex.json");
    expect_has(err, "no-such-texture.png");
    expect_has(err, "'desk', 'chair'");
}

TEST(Texture, CacheSharesDataAndNoticesRewrites) {
    std::string path = write_quad_exr("cached.exr");
    Texture a = Texture::load_bitmap(path, false), b = Texture::load_bitmap(path, false, TextureFilter::Nearest);
    EXPECT_EQ(a.bitmap().get(), b.bitmap().get());
    // The same file reached by another spelling of the path is the same entry.
    std::string other = (fs::path(path).parent_path() / "." / "cached.exr").string();
    EXPECT_EQ(Texture::load_bitmap(other, false).bitmap().get(), a.bitmap().get());
    EXPECT_NE(Texture::load_bitmap(path, true).bitmap().get(), a.bitmap().get());  // keyed by raw too
    // A rewritten file is reloaded; earlier holders keep their (immutable) data.
    Image img;
    img.width = 3;
    img.height = 1;
    img.channels = 3;
    img.data.assign(9, 0.25f);
    write_exr(path, img);
    Texture c = Texture::load_bitmap(path, false);
    EXPECT_EQ(c.bitmap()->width, 3);
    EXPECT_EQ(a.bitmap()->width, 2);
}

TEST(Texture, FromProps) {
    Props owner;
    owner.type = "diffuse";
    owner.file = temp_path("scene.json");
    owner.where = "materials.m";
    expect_rgb(texture_from_props(owner, "reflectance", Eigen::Array3f::Constant(0.5f)).eval({0, 0}),
               Eigen::Array3f::Constant(0.5f));
    owner.values["reflectance"] = 0.25f;
    EXPECT_TRUE(texture_from_props(owner, "reflectance", Eigen::Array3f::Zero()).is_constant());
    expect_rgb(texture_from_props(owner, "reflectance", Eigen::Array3f::Zero()).mean(),
               Eigen::Array3f::Constant(0.25f));
    owner.values["reflectance"] = Eigen::Array3f(0.1f, 0.2f, 0.3f);
    expect_rgb(texture_from_props(owner, "reflectance", Eigen::Array3f::Zero()).eval({0, 0}),
               Eigen::Array3f(0.1f, 0.2f, 0.3f));

    // A relative filename is taken relative to the owner's file.
    write_quad_exr("rel.exr");
    owner.values["reflectance"] = bitmap_props("rel.exr", "nearest", "clamp");
    Texture t = texture_from_props(owner, "reflectance", Eigen::Array3f::Zero());
    EXPECT_EQ(t.filter(), TextureFilter::Nearest);
    EXPECT_EQ(t.wrap(), TextureWrap::Clamp);
    expect_rgb(t.eval({0.9f, 0.1f}), kGreen);

    auto fails = [&](const std::shared_ptr<Props>& tex, const std::string& field, const std::string& msg) {
        owner.values["reflectance"] = tex;
        std::string err = error_of([&] { texture_from_props(owner, "reflectance", Eigen::Array3f::Zero()); });
        expect_has(err, "materials.m.reflectance" + field);
        expect_has(err, msg);
    };
    fails(bitmap_props("rel.exr", "bicubic"), ".filter_type", "bicubic");
    fails(bitmap_props("rel.exr", "", "wrap"), ".wrap_mode", "expected repeat, mirror or clamp");
    auto checker = bitmap_props("rel.exr");
    checker->type = "checkerboard";
    fails(checker, ".type", "unknown texture type 'checkerboard'");
    auto extra = bitmap_props("rel.exr");
    extra->values["to_uv"] = 1.f;
    fails(extra, ".to_uv", "does not support 'to_uv'");
    auto nofile = bitmap_props("rel.exr");
    nofile->values.erase("filename");
    fails(nofile, ".filename", "needs a filename");
    owner.values["reflectance"] = std::string("wood.png");
    expect_has(error_of([&] { texture_from_props(owner, "reflectance", Eigen::Array3f::Zero()); }), "a bitmap texture");
}

TEST(Texture, DiffuseWithBitmapReflectance) {
    Props p;
    p.type = "diffuse";
    p.values["reflectance"] = bitmap_props(write_quad_exr());
    auto bsdf = make_bsdf<3>(p);
    const Vec3f wi = Vec3f(0.3f, 0.1f, 1.f).normalized(), wo = Vec3f(-0.2f, 0.4f, 1.f).normalized();
    for (Vec2f uv : {Vec2f(0.25f, 0.25f), Vec2f(0.4f, 0.6f)}) {
        BSDFContext ctx;
        ctx.uv = uv;
        Eigen::Array3f rho = uv.x() == 0.25f ? kRed : Eigen::Array3f(0.42f, 0.30f, 0.49f);
        expect_rgb(bsdf->eval(ctx, wi, wo), rho * (wo.z() * kInvPi));
        expect_rgb(bsdf->albedo(ctx), rho);
        BSDFSample<3> bs = bsdf->sample(ctx, wi, 0.5f, Vec2f(0.3f, 0.7f));
        ASSERT_TRUE(bs.valid());
        expect_rgb(bs.weight, rho);
    }
    // set_spectral replaces the image by a constant.
    bsdf->set_spectral("reflectance", Eigen::Array3f(0.2f, 0.2f, 0.2f));
    BSDFContext ctx;
    ctx.uv = Vec2f(0.25f, 0.25f);
    expect_rgb(bsdf->albedo(ctx), Eigen::Array3f::Constant(0.2f));

    // Latent channels: ρ(uv) = g(uv)·s + o with g the texel's luminance; before fitting
    // s = the mean colour's luminance / g of the mean = 1 per channel, o = 0, so ρ = g(uv).
    auto latent = make_bsdf<16>(p);
    EXPECT_EQ(latent->spectral_keys(), (std::vector<std::string>{"reflectance.scale", "reflectance.offset"}));
    for (Vec2f uv : {Vec2f(0.25f, 0.25f), Vec2f(0.4f, 0.6f)}) {
        ctx.uv = uv;
        const float g = luminance(Color3(uv.x() == 0.25f ? Color3(kRed) : Color3(0.42f, 0.30f, 0.49f)));
        EXPECT_TRUE(latent->albedo(ctx).isApprox(Spectrum<16>::Constant(g), 1e-5f)) << latent->albedo(ctx).transpose();
        latent->set_spectral("reflectance.scale", Spectrum<16>::LinSpaced(-1.f, 2.f));
        latent->set_spectral("reflectance.offset", Spectrum<16>::Constant(0.1f));
        EXPECT_TRUE(latent->albedo(ctx).isApprox(Spectrum<16>::LinSpaced(-1.f, 2.f) * g + 0.1f, 1e-5f));
        // ∂(f cos)/∂s = g cos/π, ∂/∂o = cos/π (eval_grad keys 0 and 1).
        EXPECT_NEAR(latent->eval_grad(ctx, wi, wo, 0)[3], g * wo.z() * kInvPi, 1e-6f);
        EXPECT_NEAR(latent->eval_grad(ctx, wi, wo, 1)[3], wo.z() * kInvPi, 1e-6f);
        latent = make_bsdf<16>(p);
    }
    EXPECT_THROW(latent->set_spectral("reflectance", Spectrum<16>::Zero()), std::invalid_argument);
}

TEST(Texture, ObjUvsWithFlipPutTheImageTopAtVtOne) {
    // Mitsuba's convention end to end: OBJ vt (0, 1) is the image's top-left corner, after the
    // reader's flip_v (v' = 1 - v). A texture lookup there finds the top row.
    std::string obj = test::write_temp_file("uvquad.obj",
                                            "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                                            "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                                            "f 1/1 2/2 3/3 4/4\n");
    TriangleMesh m = load_obj(obj, true);
    ASSERT_EQ(m.uvs.size(), 4u);
    Texture t = load(write_quad_exr(), TextureFilter::Nearest, TextureWrap::Clamp);
    auto at_vertex = [&](const Vec3f& p) {
        for (size_t i = 0; i < m.positions.size(); ++i)
            if (m.positions[i].isApprox(p)) return t.eval(m.uvs[i] * 0.98f + Vec2f::Constant(0.01f));  // just inside
        ADD_FAILURE() << "no vertex at " << p.transpose();
        return Eigen::Array3f(Eigen::Array3f::Zero());
    };
    expect_rgb(at_vertex({0, 1, 0}), kRed);     // vt (0, 1): top-left
    expect_rgb(at_vertex({1, 1, 0}), kGreen);   // vt (1, 1): top-right
    expect_rgb(at_vertex({0, 0, 0}), kBlue);    // vt (0, 0): bottom-left
    expect_rgb(at_vertex({1, 0, 0}), kYellow);  // vt (1, 0): bottom-right
}

TEST(Texture, JsonSceneResolvesFilenamesAndNamesUnsupportedUses) {
    write_quad_exr("json-tex.exr");
    auto scene_json = [](const std::string& material) {
        return R"({"camera": {"width": 4, "height": 4}, "materials": {"wood": )" + material +
               R"(}, "shapes": [{"type": "rectangle", "material": "wood"}]})";
    };
    std::string path =
        test::write_temp_file("textured.json", scene_json(R"({"type": "twosided", "bsdf": {"type": "diffuse",
        "reflectance": {"type": "bitmap", "filename": "json-tex.exr", "raw": false, "filter_type": "nearest"}}})"));
    Scene s = load_scene(path);
    auto tex = s.materials[0].get_child("bsdf")->get_child("reflectance");
    ASSERT_TRUE(tex);
    std::string file = std::get<std::string>(tex->values.at("filename"));
    EXPECT_TRUE(fs::path(file).is_absolute()) << file;
    EXPECT_TRUE(fs::equivalent(file, temp_path("json-tex.exr")));

    // A texture on a key its BSDF reads as a plain colour.
    path = test::write_temp_file("textured-conductor.json", scene_json(R"({"type": "conductor",
        "specular_reflectance": {"type": "bitmap", "filename": "json-tex.exr"}})"));
    std::string err = error_of([&] { load_scene(path); });
    expect_has(err, "materials.wood.specular_reflectance");
    expect_has(err, "textured specular_reflectance on conductor is not supported yet");
}

TEST(Texture, PlasticsWithBitmapDiffuseEqualTheConstantAtThatTexel) {
    // A textured plastic at uv must equal the same plastic with the texel's colour as a constant.
    const Vec3f wi = Vec3f(0.3f, 0.1f, 1.f).normalized(), wo = Vec3f(-0.2f, 0.4f, 1.f).normalized();
    for (const char* type : {"plastic", "roughplastic"})
        for (bool nonlinear : {false, true}) {
            Props tex;
            tex.type = type;
            tex.values["diffuse_reflectance"] = bitmap_props(write_quad_exr());
            tex.values["nonlinear"] = nonlinear;
            Props flat = tex;
            flat.values["diffuse_reflectance"] = Eigen::Array3f(kRed);
            auto a = make_bsdf<3>(tex), b = make_bsdf<3>(flat);
            BSDFContext ctx;
            ctx.uv = Vec2f(0.25f, 0.25f);  // the red texel, as in DiffuseWithBitmapReflectance
            expect_rgb(a->eval(ctx, wi, wo), b->eval(ctx, wi, wo));
            expect_rgb(a->albedo(ctx), b->albedo(ctx));
            for (float u1 : {0.1f, 0.9f}) {
                BSDFSample<3> sa = a->sample(ctx, wi, u1, Vec2f(0.3f, 0.7f)),
                              sb = b->sample(ctx, wi, u1, Vec2f(0.3f, 0.7f));
                ASSERT_EQ(sa.valid(), sb.valid());
                if (sa.valid()) expect_rgb(sa.weight, sb.weight);
            }
            ctx.uv = Vec2f(0.75f, 0.75f);  // another texel: must differ from the red constant
            EXPECT_FALSE(a->eval(ctx, wi, wo).isApprox(b->eval(ctx, wi, wo), 1e-3f)) << type;
        }
}
