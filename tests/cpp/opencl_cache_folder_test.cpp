// SPDX-License-Identifier: GPL-3.0-or-later
// The OpenCL program cache folder per system convention, from given environment values: the
// Windows and macOS answers are checked here on Linux, where they cannot run.
#include <gtest/gtest.h>

#include <map>
#include <string>

#include "opencl/cache_folder.h"

namespace sdf::cl {
namespace {

using Env = std::map<std::string, std::string>;

std::string folder(CacheConvention convention, const Env& env) {
  return cache_folder(
      convention,
      [&env](const char* name) {
        const auto it = env.find(name);
        return it == env.end() ? nullptr : it->second.c_str();
      },
      convention == CacheConvention::kWindows ? "C:\\Temp" : "/tmp");
}

// Every variable a convention might read, so a wrong choice shows as a wrong folder.
const Env kAll = {{"HOME", "/home/ana"},
                  {"XDG_CACHE_HOME", "/home/ana/xdg"},
                  {"LOCALAPPDATA", "C:\\Users\\ana\\AppData\\Local"},
                  {"APPDATA", "C:\\Users\\ana\\AppData\\Roaming"},
                  {"USERPROFILE", "C:\\Users\\ana"}};

TEST(OpenclCacheFolder, LinuxFollowsXdgThenHomeDotCache) {
  EXPECT_EQ(folder(CacheConvention::kXdg, kAll), "/home/ana/xdg/shape_diameter/opencl");
  Env env = kAll;
  env.erase("XDG_CACHE_HOME");
  EXPECT_EQ(folder(CacheConvention::kXdg, env), "/home/ana/.cache/shape_diameter/opencl");
  env["XDG_CACHE_HOME"] = "";  // set but empty: the XDG spec says to ignore it
  EXPECT_EQ(folder(CacheConvention::kXdg, env), "/home/ana/.cache/shape_diameter/opencl");
}

TEST(OpenclCacheFolder, MacosUsesLibraryCachesNotXdg) {
  EXPECT_EQ(folder(CacheConvention::kMacOS, kAll),
            "/home/ana/Library/Caches/shape_diameter/opencl");
}

TEST(OpenclCacheFolder, WindowsUsesLocalAppDataWithBackslashes) {
  EXPECT_EQ(folder(CacheConvention::kWindows, kAll),
            "C:\\Users\\ana\\AppData\\Local\\shape_diameter\\opencl");
  Env env = kAll;
  env["LOCALAPPDATA"] = "C:\\Users\\ana\\AppData\\Local\\";  // a trailing separator
  EXPECT_EQ(folder(CacheConvention::kWindows, env),
            "C:\\Users\\ana\\AppData\\Local\\shape_diameter\\opencl");
}

TEST(OpenclCacheFolder, SdfCacheDirWinsEverywhere) {
  Env env = kAll;
  env["SDF_CACHE_DIR"] = "/data/cache/";
  EXPECT_EQ(folder(CacheConvention::kXdg, env), "/data/cache/opencl");
  EXPECT_EQ(folder(CacheConvention::kMacOS, env), "/data/cache/opencl");
  env["SDF_CACHE_DIR"] = "D:\\cache";
  EXPECT_EQ(folder(CacheConvention::kWindows, env), "D:\\cache\\opencl");
}

TEST(OpenclCacheFolder, TempFolderWhereTheConventionsVariablesAreMissing) {
  // Only the other systems' variables are set: none of them may be taken.
  EXPECT_EQ(folder(CacheConvention::kXdg, {{"LOCALAPPDATA", "C:\\x"}}),
            "/tmp/shape_diameter/opencl");
  EXPECT_EQ(folder(CacheConvention::kMacOS, {{"XDG_CACHE_HOME", "/x"}}),
            "/tmp/shape_diameter/opencl");
  EXPECT_EQ(folder(CacheConvention::kWindows, {{"HOME", "/home/ana"}, {"LOCALAPPDATA", ""}}),
            "C:\\Temp\\shape_diameter\\opencl");
  EXPECT_EQ(folder(CacheConvention::kXdg, {}), "/tmp/shape_diameter/opencl");
}

TEST(OpenclCacheFolder, HostConventionMatchesTheSystemCompiledFor) {
#if defined(_WIN32)
  EXPECT_EQ(host_cache_convention(), CacheConvention::kWindows);
#elif defined(__APPLE__)
  EXPECT_EQ(host_cache_convention(), CacheConvention::kMacOS);
#else
  EXPECT_EQ(host_cache_convention(), CacheConvention::kXdg);
#endif
}

}  // namespace
}  // namespace sdf::cl
