// The cache directory rule of the XDG Base Directory Specification, by hand.
#include <gtest/gtest.h>

#include "omniloc/detail/cache_dir.hpp"

namespace omniloc {
namespace {

TEST(CacheDir, XdgCacheHomeWinsWhenAbsolute) {
  EXPECT_EQ(user_cache_dir("/var/cache/me", "/home/me"),
            std::filesystem::path("/var/cache/me/omniloc"));
}

TEST(CacheDir, HomeDotCacheOtherwise) {
  EXPECT_EQ(user_cache_dir(nullptr, "/home/me"), std::filesystem::path("/home/me/.cache/omniloc"));
  EXPECT_EQ(user_cache_dir("", "/home/me"), std::filesystem::path("/home/me/.cache/omniloc"));
  // The specification: a relative XDG_CACHE_HOME is invalid and ignored.
  EXPECT_EQ(user_cache_dir("relative/cache", "/home/me"),
            std::filesystem::path("/home/me/.cache/omniloc"));
}

TEST(CacheDir, NeitherUsableIsAnErrorNamingBoth) {
  try {
    (void)user_cache_dir(nullptr, "");
    FAIL() << "no error";
  } catch (const CacheDirError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("XDG_CACHE_HOME is unset"), std::string::npos) << what;
    EXPECT_NE(what.find("HOME is ''"), std::string::npos) << what;
    EXPECT_NE(what.find("--db"), std::string::npos) << what;
  }
  EXPECT_THROW((void)user_cache_dir("rel", "also/rel"), CacheDirError);
}

}  // namespace
}  // namespace omniloc
