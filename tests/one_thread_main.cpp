// main() of the test binaries declared with mudcrack_test(... ONE_THREAD): their tests run on
// one thread unless a test says otherwise (the machine is shared; determinism across thread
// counts has its own tests), set by a gtest environment before the first test.
#include <gtest/gtest.h>

#include "sim/core/parallel.h"

namespace {

class OneThreadEnvironment : public ::testing::Environment {
public:
    void SetUp() override { mudcrack::set_thread_count(1); }
};

}  // namespace

int main(int argc, char** argv) {
    ::testing::InitGoogleTest(&argc, argv);
    ::testing::AddGlobalTestEnvironment(new OneThreadEnvironment);  // gtest owns and deletes it
    return RUN_ALL_TESTS();
}
