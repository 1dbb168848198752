# Debian 12 packages only; the Makefile installs them (APT_PACKAGES, `make deps`).
find_package(Eigen3 3.4 REQUIRED NO_MODULE)       # Eigen3::Eigen
find_package(OpenMP REQUIRED)                     # OpenMP::OpenMP_CXX
find_package(TBB CONFIG REQUIRED)                 # TBB::tbb (oneTBB's own config)
find_package(nlohmann_json 3.10 REQUIRED)         # nlohmann_json::nlohmann_json
find_package(CLI11 REQUIRED)                      # CLI11::CLI11
find_package(ZLIB REQUIRED)                       # ZLIB::ZLIB (file checksums; PNG needs it too)
find_package(PNG REQUIRED)                        # PNG::PNG
find_package(assimp REQUIRED)                     # assimp::assimp
find_package(PkgConfig REQUIRED)
pkg_check_modules(OSMESA REQUIRED IMPORTED_TARGET osmesa)   # PkgConfig::OSMESA
# libopenvdb-dev ships only a find module, under the multiarch lib's cmake/OpenVDB folder
if(CMAKE_LIBRARY_ARCHITECTURE)
  list(APPEND CMAKE_MODULE_PATH /usr/lib/${CMAKE_LIBRARY_ARCHITECTURE}/cmake/OpenVDB)
endif()
list(APPEND CMAKE_MODULE_PATH /usr/lib/x86_64-linux-gnu/cmake/OpenVDB /usr/lib/aarch64-linux-gnu/cmake/OpenVDB)
find_package(OpenVDB REQUIRED)                    # OpenVDB::openvdb (needs Boost::iostreams)
find_package(CGAL REQUIRED)                       # CGAL::CGAL, used only by pipeline/init
if(MUDCRACK_BUILD_TESTS)
  find_package(GTest REQUIRED)                    # GTest::gtest GTest::gtest_main
  include(GoogleTest)
endif()
if(MUDCRACK_BUILD_BENCHMARKS)
  find_package(benchmark REQUIRED)                # benchmark::benchmark
endif()
