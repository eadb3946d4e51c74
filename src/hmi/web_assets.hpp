// The page's files, compiled into the binary (src/hmi/web: the page; three.js and uPlot from
// npm, pinned by web/package-lock.json).
#pragma once

#include <string_view>

namespace cncore::hmi {

struct WebAsset {
  std::string_view path;  // as requested: "/", "/app.js", "/vendor/…"
  std::string_view content_type;
  std::string_view bytes;
};

// Null when no file is served at that path.
const WebAsset* find_web_asset(std::string_view path);

}  // namespace cncore::hmi
