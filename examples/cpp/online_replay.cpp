// A SLAM front end's use of inexact-loops' C ABI: replay a TUM trajectory (one pose a line,
// `t x y z qx qy qz qw`) pose by pose, as a robot would produce it, and print the loop-closure
// candidates the online sampler picks at each keyframe, one line each:
//
//     keyframe j component distance
//
// (the pose just pushed, the earlier pose to match it with, the loop component of the pair, and
// their distance in the metric's unit, printed exactly with 17 significant digits).
//
// Build (from the repository's root; `make test-cpp` does this and runs it):
//
//     cargo build --release -p loops-capi
//     c++ -std=c++17 -O2 -Icrates/loops-capi/include examples/cpp/online_replay.cpp
//         target/release/libinexact_loops.a -lpthread -ldl -lm -o online_replay    # one line
//     ./online_replay drive.tum --gamma 40 --rate 0.05 --cap-per-minute 2
//
// Options (the defaults are the library's, from loops_sampler_options_default):
//   --gamma G               the threshold, the metric's unit (required)
//   --metric M              euclidean (positions x y z; the default) or an se3 metric such as
//                           "se3(rotation_weight_m_per_rad=10)" (whole poses; quaternions are
//                           normalised as read)
//   --rate R                σ_ρ: candidates per component per pose
//   --cap-per-minute C      at most C candidates per minute per component
//   --cap-per-metre C       at most C candidates per metre of travel per component
//   --no-first              no candidate at a component's first appearance
//   --separation-path P     only pairs at least P apart along the path
//   --separation-time S     only pairs at least S seconds apart
//   --seed N                the seed of the random choices
//
// Errors (a bad line of the file, a pose the library refuses, a bad option) are one line on
// stderr and exit code 2.

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "inexact_loops.h"

namespace {

// Throws the library's message when a call did not succeed.
void check(LoopsStatus status, const char* what) {
    if (status != LOOPS_STATUS_OK) {
        throw std::runtime_error(std::string(what) + ": " + loops_last_error());
    }
}

// The handles, freed by their owners.
struct OnlineDeleter {
    void operator()(LoopsOnline* online) const { loops_online_free(online); }
};
struct SamplerDeleter {
    void operator()(LoopsSampler* sampler) const { loops_sampler_free(sampler); }
};
using Online = std::unique_ptr<LoopsOnline, OnlineDeleter>;
using Sampler = std::unique_ptr<LoopsSampler, SamplerDeleter>;

struct Options {
    std::string path;
    double gamma = 0.0;
    bool gamma_given = false;
    std::string metric = "euclidean";
    LoopsSamplerOptions sampler{};
};

double number(const std::string& flag, const char* text) {
    char* end = nullptr;
    double value = std::strtod(text, &end);
    if (end == text || *end != '\0') {
        throw std::runtime_error(flag + " takes a number, got \"" + text + "\"");
    }
    return value;
}

Options parse(int argc, char** argv) {
    Options options;
    check(loops_sampler_options_default(&options.sampler), "loops_sampler_options_default");
    for (int k = 1; k < argc; ++k) {
        std::string flag = argv[k];
        auto value = [&]() -> const char* {
            if (k + 1 >= argc) throw std::runtime_error(flag + " takes a value");
            return argv[++k];
        };
        if (flag == "--gamma") {
            options.gamma = number(flag, value());
            options.gamma_given = true;
        } else if (flag == "--metric") {
            options.metric = value();
        } else if (flag == "--rate") {
            options.sampler.rate = number(flag, value());
        } else if (flag == "--cap-per-minute") {
            options.sampler.cap_kind = LOOPS_CAP_KIND_PER_MINUTE;
            options.sampler.cap_value = number(flag, value());
        } else if (flag == "--cap-per-metre") {
            options.sampler.cap_kind = LOOPS_CAP_KIND_PER_METRE;
            options.sampler.cap_value = number(flag, value());
        } else if (flag == "--no-first") {
            options.sampler.first_on_appearance = false;
        } else if (flag == "--separation-path") {
            options.sampler.separation_path = number(flag, value());
        } else if (flag == "--separation-time") {
            options.sampler.separation_time_s = number(flag, value());
        } else if (flag == "--seed") {
            options.sampler.seed = std::strtoull(value(), nullptr, 10);
        } else if (!flag.empty() && flag[0] == '-') {
            throw std::runtime_error("unknown option " + flag);
        } else if (options.path.empty()) {
            options.path = flag;
        } else {
            throw std::runtime_error("one TUM file, got a second: " + flag);
        }
    }
    if (options.path.empty() || !options.gamma_given) {
        throw std::runtime_error("usage: online_replay FILE.tum --gamma G [--metric M] [--rate R] ...");
    }
    return options;
}

}  // namespace

int main(int argc, char** argv) {
    try {
        Options options = parse(argc, argv);
        // Euclidean measures positions; the se3 metrics whole poses with their quaternions.
        bool poses = options.metric.rfind("se3", 0) == 0;
        size_t dim = poses ? 7 : 3;

        LoopsOnline* raw_online = nullptr;
        check(loops_online_new(options.metric.c_str(), dim, options.gamma, &raw_online), "loops_online_new");
        Online online(raw_online);
        LoopsSampler* raw_sampler = nullptr;
        check(loops_sampler_new(&options.sampler, &raw_sampler), "loops_sampler_new");
        Sampler sampler(raw_sampler);

        std::ifstream file(options.path);
        if (!file) throw std::runtime_error("cannot open " + options.path);
        std::vector<LoopsCandidate> candidates(64);
        std::string line;
        for (size_t line_number = 1; std::getline(file, line); ++line_number) {
            if (line.empty() || line[0] == '#') continue;
            // Eight numbers (strtod also reads nan and inf, which the library then refuses).
            std::istringstream fields(line);
            std::string field;
            double row[8];
            int numbers = 0;
            while (fields >> field) {
                char* end = nullptr;
                double value = std::strtod(field.c_str(), &end);
                if (numbers == 8 || end == field.c_str() || *end != '\0') {
                    numbers = -1;
                    break;
                }
                row[numbers++] = value;
            }
            if (numbers != 8) {
                throw std::runtime_error(options.path + ":" + std::to_string(line_number) +
                                         ": expected 8 numbers: t x y z qx qy qz qw");
            }
            double t = row[0];
            double* v = row + 1;
            if (poses) {
                double norm = std::sqrt(v[3] * v[3] + v[4] * v[4] + v[5] * v[5] + v[6] * v[6]);
                for (int q = 3; q < 7; ++q) v[q] /= norm;
            }
            LoopsUpdate update;
            LoopsStatus pushed = loops_online_push(online.get(), t, v, dim, &update);
            if (pushed != LOOPS_STATUS_OK) {
                throw std::runtime_error(options.path + ":" + std::to_string(line_number) + ": " + loops_last_error());
            }
            size_t count = 0;
            check(loops_sampler_offer(sampler.get(), online.get(), candidates.data(), candidates.size(), &count),
                  "loops_sampler_offer");
            if (count > candidates.size()) {
                // More than the buffer holds: read the rest from the sampler.
                size_t held = candidates.size();
                candidates.resize(count);
                size_t written = 0;
                check(loops_sampler_candidates(sampler.get(), held, candidates.data() + held, count - held, &written),
                      "loops_sampler_candidates");
            }
            for (size_t k = 0; k < count; ++k) {
                const LoopsCandidate& c = candidates[k];
                std::printf("%zu %zu %u %.17g\n", c.keyframe, c.j, c.component, c.distance);
            }
        }
        std::fprintf(stderr, "online_replay: %zu poses, %zu loop components\n", loops_online_len(online.get()),
                     loops_online_component_count(online.get()));
        return 0;
    } catch (const std::exception& error) {
        std::fprintf(stderr, "online_replay: error: %s\n", error.what());
        return 2;
    }
}
