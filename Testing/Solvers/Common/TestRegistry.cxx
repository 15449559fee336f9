// Tests of the registry every pluggable family uses (Common/Registry.h).
#include "Error.h"
#include "Registry.h"

#include <gtest/gtest.h>

namespace
{

struct Shape
{
  virtual ~Shape() = default;
  virtual int Corners() const = 0;
};
struct Triangle : Shape
{
  int Corners() const override { return 3; }
};
struct Square : Shape
{
  int Corners() const override { return 4; }
};
struct ShapeTraits
{
  bool Regular = true;
};

translucency::Registry<Shape, ShapeTraits> MakeShapes()
{
  translucency::Registry<Shape, ShapeTraits> shapes("shape");
  shapes.Add({ "triangle", [] { return std::make_unique<Triangle>(); }, {}, "three corners" });
  shapes.Add({ "Square", [] { return std::make_unique<Square>(); }, { false }, "four corners" });
  return shapes;
}

} // namespace

TEST(Registry, ListsNamesInOrderAndCreatesCaseInsensitively)
{
  const auto shapes = MakeShapes();
  EXPECT_EQ(shapes.GetNames(), (std::vector<std::string>{ "triangle", "square" }));
  EXPECT_EQ(shapes.Create("TRIANGLE")->Corners(), 3);
  EXPECT_EQ(shapes.Create("square")->Corners(), 4);
  EXPECT_FALSE(shapes.Get("square").Properties.Regular);
  EXPECT_EQ(shapes.Find("circle"), nullptr);
}

TEST(Registry, UnknownNameListsTheKnownOnes)
{
  const auto shapes = MakeShapes();
  try
  {
    shapes.Create("circle");
    FAIL() << "no error";
  }
  catch (const translucency::Error& e)
  {
    EXPECT_STREQ(e.what(), "unknown shape 'circle' (known shapes: triangle, square)");
  }
}

TEST(Registry, RejectsADuplicateName)
{
  auto shapes = MakeShapes();
  EXPECT_THROW(
    shapes.Add({ "TRIANGLE", [] { return std::make_unique<Triangle>(); }, {}, "again" }),
    translucency::Error);
}

TEST(Registry, HelpHasOneAlignedLinePerEntry)
{
  EXPECT_EQ(MakeShapes().FormatHelp(), "  triangle  three corners\n  square    four corners\n");
}
