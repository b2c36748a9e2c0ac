// Which sanitizer instruments this test binary, for the preprocessor: GCC defines __SANITIZE_ADDRESS__
// and __SANITIZE_THREAD__; clang 16 (the ASan + UBSan tree's compiler, scripts/build.sh) defines neither
// and answers __has_feature instead.
#pragma once

#if defined(__SANITIZE_ADDRESS__)
#define AEROTRACK_TEST_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define AEROTRACK_TEST_ASAN 1
#endif
#endif

#if defined(__SANITIZE_THREAD__)
#define AEROTRACK_TEST_TSAN 1
#elif defined(__has_feature)
#if __has_feature(thread_sanitizer)
#define AEROTRACK_TEST_TSAN 1
#endif
#endif
