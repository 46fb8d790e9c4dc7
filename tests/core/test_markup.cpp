// Markup for JUnit and report.html (rig/core/markup.hpp): the five markup characters as
// entities, and the C0 controls XML 1.0 cannot carry shown as text (a DUT-reported serial with
// 0x01 made junit.xml not well-formed).
#include <gtest/gtest.h>

#include "rig/core/markup.hpp"

namespace {

TEST(Markup, EscapesMarkupAndShowsControlsAsText) {
  EXPECT_EQ(rig::markup_escape("a<b>&\"'"), "a&lt;b&gt;&amp;&quot;&#39;");
  EXPECT_EQ(rig::markup_escape("A\tB\x01\x1f\n"), "A\tB\\x01\\x1F\n");
  EXPECT_EQ(rig::markup_escape("\xd0\x96"), "\xd0\x96");  // UTF-8 passes as it is
}

}  // namespace
