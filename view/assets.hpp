#pragma once
/// The page's files, embedded at build time from view/web/ (view/embed.cmake writes assets.cpp into
/// the build tree: nothing generated is committed, and the binary serves every asset itself).
#include <cstddef>
#include <string_view>

namespace shapeform::view {

struct Asset {
  std::string_view path;          ///< URL path: "/" for index.html, "/view.js", ...
  std::string_view content_type;  ///< "text/html; charset=utf-8", ...
  std::string_view body;
};

/// Every embedded file.
extern const Asset kAssets[];
extern const std::size_t kAssetCount;

}  // namespace shapeform::view
