// convert_file keeps the source's length unit in STEP and IGES outputs (or
// writes the one asked for), with the geometry scaled so that it stays the
// same size.
//
// The fixture is an IGES file in inches written here by OCCT's own
// IGESControl_Writer("INCH"): a 2 x 1 x 0.5 inch box. Each output is read back
// with OCCT's plain readers, independently of the project's reader: the unit
// the file declares (STEPControl_Reader::FileUnits, the IGES global section)
// and its box in mm (OCCT converts to mm on reading) must match the source.
//  * InchIgesToStep:   inch IGES -> STEP declares INCH, the same box.
//  * UnitsAsked:       inch IGES -> STEP in mm, -> IGES in cm: declared as
//                      asked, the same box; STL refuses a unit (it has its own).
//  * Names:            the unit names both ways, and IGES's unit flags.
#include <gtest/gtest.h>

#include <BRepBndLib.hxx>
#include <BRepPrimAPI_MakeBox.hxx>
#include <Bnd_Box.hxx>
#include <IGESControl_Controller.hxx>
#include <IGESControl_Reader.hxx>
#include <IGESControl_Writer.hxx>
#include <IGESData_GlobalSection.hxx>
#include <IGESData_IGESModel.hxx>
#include <STEPControl_Reader.hxx>
#include <TColStd_SequenceOfAsciiString.hxx>

#include <string>

#include "core/error.h"
#include "importer/importer.h"
#include "tests/support/fixtures.h"

namespace {

constexpr double kMmPerInch = 25.4;
// The box's extent in inches.
constexpr double kBoxInches[3] = {2.0, 1.0, 0.5};
// Written with 15 significant digits and scaled twice (inch -> mm on reading,
// mm -> the target unit on writing): far closer than this.
constexpr double kBoxTolerance = 1e-6;

std::string out_path(const std::string& name) { return nurbsrt::test::fixture_dir() + "/units-" + name; }

// The fixture described at the top.
std::string inch_iges() {
    static const std::string path = [] {
        const std::string p = out_path("box_inch.igs");
        IGESControl_Controller::Init();
        // The shape is in OCCT's mm; the writer scales it to the file's inches.
        const TopoDS_Shape box =
            BRepPrimAPI_MakeBox(kBoxInches[0] * kMmPerInch, kBoxInches[1] * kMmPerInch, kBoxInches[2] * kMmPerInch)
                .Shape();
        IGESControl_Writer w("INCH", 1);
        if (!w.AddShape(box) || (w.ComputeModel(), !w.Write(p.c_str())))
            throw std::runtime_error("inch IGES fixture: write failed");
        return p;
    }();
    return path;
}

struct ReadBack {
    std::string unit;  // as the file declares it
    Bnd_Box box;       // in mm
};

ReadBack read_step(const std::string& path) {
    STEPControl_Reader r;
    ReadBack b;
    EXPECT_EQ(r.ReadFile(path.c_str()), IFSelect_RetDone) << path;
    TColStd_SequenceOfAsciiString lengths, angles, solid_angles;
    r.FileUnits(lengths, angles, solid_angles);
    if (lengths.Length() > 0) b.unit = lengths.Value(1).ToCString();
    r.TransferRoots();
    BRepBndLib::Add(r.OneShape(), b.box, Standard_False);
    return b;
}

ReadBack read_iges(const std::string& path) {
    IGESControl_Reader r;
    ReadBack b;
    EXPECT_EQ(r.ReadFile(path.c_str()), IFSelect_RetDone) << path;
    b.unit = r.IGESModel()->GlobalSection().UnitName()->ToCString();
    r.TransferRoots();
    BRepBndLib::Add(r.OneShape(), b.box, Standard_False);
    return b;
}

void expect_the_box(const Bnd_Box& box, const std::string& what) {
    ASSERT_FALSE(box.IsVoid()) << what;
    double lo[3], hi[3];
    box.Get(lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]);
    for (int i = 0; i < 3; ++i) {
        EXPECT_NEAR(lo[i], 0.0, kBoxTolerance) << what << " axis " << i;
        EXPECT_NEAR(hi[i], kBoxInches[i] * kMmPerInch, kBoxTolerance) << what << " axis " << i;
    }
}

TEST(ConvertUnits, FixtureIsInInches) {
    const ReadBack b = read_iges(inch_iges());
    EXPECT_EQ(b.unit, "INCH");
    expect_the_box(b.box, "the inch IGES fixture");
}

// The inch fixture converted to `name` without a unit asked: the report and
// the written file say inch, and the model keeps its size.
void expect_inch_kept(const std::string& name, ReadBack (*read)(const std::string&)) {
    const std::string out = out_path(name);
    const nurbsrt::ConvertReport r = nurbsrt::convert_file(inch_iges(), out);
    EXPECT_EQ(r.in_units, "inch") << name;
    EXPECT_EQ(r.out_units, "inch") << name;
    const ReadBack b = read(out);
    EXPECT_EQ(b.unit, "INCH") << name;
    expect_the_box(b.box, "inch IGES -> " + name);
}

TEST(ConvertUnits, InchIgesToStepWritesInch) { expect_inch_kept("inch.step", read_step); }
TEST(ConvertUnits, InchIgesToIgesWritesInch) { expect_inch_kept("inch.igs", read_iges); }

TEST(ConvertUnits, UnitsAskedForAreWrittenTheModelStaysItsSize) {
    nurbsrt::ConvertOptions mm;
    mm.units = nurbsrt::LengthUnit::mm;
    const std::string step = out_path("asked-mm.step");
    EXPECT_EQ(nurbsrt::convert_file(inch_iges(), step, mm).out_units, "mm");
    const ReadBack s = read_step(step);
    EXPECT_EQ(s.unit, "millimetre");  // as STEPControl_Reader::FileUnits spells SI units
    expect_the_box(s.box, "inch IGES -> STEP in mm");

    nurbsrt::ConvertOptions cm;
    cm.units = nurbsrt::LengthUnit::cm;
    const std::string igs = out_path("asked-cm.igs");
    EXPECT_EQ(nurbsrt::convert_file(inch_iges(), igs, cm).out_units, "cm");
    const ReadBack i = read_iges(igs);
    EXPECT_EQ(i.unit, "CM");
    expect_the_box(i.box, "inch IGES -> IGES in cm");
}

TEST(ConvertUnits, MeshOutputsRefuseAUnit) {
    nurbsrt::ConvertOptions inch;
    inch.units = nurbsrt::LengthUnit::inch;
    try {
        nurbsrt::convert_file(inch_iges(), out_path("refused.stl"), inch);
        FAIL() << "no error";
    } catch (const nurbsrt::Error& e) {
        EXPECT_EQ(e.code(), nurbsrt::ErrorCode::invalid_argument);
    }
}

// A file without a unit (STL, VRML, BREP) cannot say the source was in
// inches: the coordinates are mm, and the report says so (a warning, which
// strict refuses); glb states its metres, STEP keeps the inch: no warning.
TEST(ConvertUnits, UnitlessOutputsWarnTheSourcesUnitIsNotCarried) {
    for (const char* ext : {".stl", ".wrl", ".brep"}) {
        const nurbsrt::ConvertReport r = nurbsrt::convert_file(inch_iges(), out_path(std::string("unitless") + ext));
        ASSERT_FALSE(r.warnings.empty()) << ext;
        EXPECT_NE(r.warnings.back().find("the source is in inch; "), std::string::npos) << r.warnings.back();
        EXPECT_NE(r.warnings.back().find(" files have no unit: the coordinates are written in mm"), std::string::npos)
            << r.warnings.back();
    }
    for (const char* ext : {".glb", ".step"})
        for (const std::string& w : nurbsrt::convert_file(inch_iges(), out_path(std::string("stated") + ext)).warnings)
            EXPECT_EQ(w.find("no unit"), std::string::npos) << ext << ": " << w;
    // A source in mm written as mm loses nothing.
    for (const std::string& w : nurbsrt::convert_file(nurbsrt::test::box_with_holes(), out_path("mm.stl")).warnings)
        EXPECT_EQ(w.find("no unit"), std::string::npos) << w;
}

TEST(ConvertUnits, NamesAndIgesFlags) {
    for (const std::string& n : nurbsrt::length_unit_names()) {
        const auto u = nurbsrt::length_unit_from_name(n);
        ASSERT_TRUE(u.has_value()) << n;
        EXPECT_EQ(nurbsrt::length_unit_name(*u), n);
        EXPECT_EQ(nurbsrt::length_unit_from_iges_flag(nurbsrt::iges_unit_flag(*u)), *u) << n;
    }
    EXPECT_EQ(nurbsrt::length_unit_names().size(), 10u);
    EXPECT_FALSE(nurbsrt::length_unit_from_name("").has_value());
    EXPECT_FALSE(nurbsrt::length_unit_from_name("INCH").has_value());  // names are lowercase
    EXPECT_EQ(nurbsrt::iges_unit_flag(nurbsrt::LengthUnit::inch), 1);  // IGES 5.3 global parameter 14
    EXPECT_EQ(nurbsrt::iges_unit_flag(nurbsrt::LengthUnit::mm), 2);
    EXPECT_EQ(nurbsrt::iges_unit_flag(nurbsrt::LengthUnit::cm), 10);
    EXPECT_EQ(nurbsrt::length_unit_from_iges_flag(3), nurbsrt::LengthUnit::unknown);
}

}  // namespace
