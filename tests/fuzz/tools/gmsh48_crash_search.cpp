// Mutation search for files that crash libgmsh 4.8's own MSH reader: the read path cdemblast
// had before issue 10 (gmsh::open, then the extraction of the Gmsh model). Not built by
// default and not part of the program: it documents where the regressions in
// tests/fuzz/regressions/msh/gmsh48_*.msh come from (docs/input_safety.md). One forked child
// per try (Gmsh initialised once); a child killed by a signal keeps its input as crash_N.msh and
// a backtrace as bt_crash_N.msh.txt.
//   g++ -std=c++20 -O1 -Isrc tests/fuzz/tools/gmsh48_crash_search.cpp build/libcdem.a -lgmsh \
//     -lfmt -lspdlog -fopenmp -lz -o gmsh48_crash_search
//   ./gmsh48_crash_search 50000 7 tests/fuzz/corpus_msh/gen_*v2.2* tests/fuzz/corpus_msh/gen_*v4.1*
#include <execinfo.h>
#include <fcntl.h>
#include <gmsh.h>
#include <signal.h>
#include <spdlog/spdlog.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "cdem/mesh/gmsh_io.hpp"
static void handler(int sig) {
  void* fr[12];
  int n = backtrace(fr, 12);
  int fd = ::open("bt.txt", O_WRONLY | O_CREAT | O_TRUNC, 0644);
  backtrace_symbols_fd(fr, n, fd);
  ::close(fd);
  _exit(128 + sig);
}
int main(int argc, char** argv) {
  std::vector<std::string> seeds;
  for (int i = 3; i < argc; ++i) {
    std::ifstream f(argv[i], std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    seeds.push_back(ss.str());
  }
  const long tries = std::stol(argv[1]);
  std::mt19937_64 rng(std::stoul(argv[2]));
  spdlog::set_level(spdlog::level::off);
  gmsh::initialize(0, nullptr, false);
  gmsh::option::setNumber("General.Terminal", 0);
  long crashes = 0;
  const char* nums[] = {"0",          "-1",          "1",          "2",
                        "3",          "7",           "99",         "4294967295",
                        "2147483647", "-2147483648", "1000000000", "18446744073709551615",
                        "nan",        "1e300",       "15",         "5"};
  for (long t = 0; t < tries; ++t) {
    std::string s = seeds[rng() % seeds.size()];
    const int nm = 1 + rng() % 3;
    for (int m = 0; m < nm; ++m) {
      const int kind = rng() % 5;
      if (s.empty()) break;
      size_t p = rng() % s.size();
      if (kind == 0)
        s[p] ^= 1 << (rng() % 8);
      else if (kind == 1 || kind == 2) {  // replace a number token
        while (p < s.size() && !isdigit((unsigned char)s[p])) ++p;
        size_t e = p;
        while (e < s.size() && (isdigit((unsigned char)s[e]) || s[e] == '.' || s[e] == '-')) ++e;
        if (p < s.size()) s.replace(p, e - p, nums[rng() % 16]);
      } else if (kind == 3) {  // delete a line
        size_t a = s.rfind('\n', p);
        a = a == std::string::npos ? 0 : a + 1;
        size_t b = s.find('\n', p);
        if (b != std::string::npos) s.erase(a, b - a + 1);
      } else {  // duplicate a line
        size_t a = s.rfind('\n', p);
        a = a == std::string::npos ? 0 : a + 1;
        size_t b = s.find('\n', p);
        if (b != std::string::npos) s.insert(a, s.substr(a, b - a + 1));
      }
    }
    {
      std::ofstream f("try.msh", std::ios::binary);
      f << s;
    }
    pid_t pid = fork();
    if (pid == 0) {
      signal(SIGSEGV, handler);
      signal(SIGBUS, handler);
      signal(SIGFPE, handler);
      signal(SIGABRT, handler);
      signal(SIGILL, handler);
      alarm(10);
      struct rlimit rl {
        2000000000, 2000000000
      };
      setrlimit(RLIMIT_AS, &rl);
      try {
        gmsh::model::add("m");
        gmsh::open("try.msh");
        cdem::detail::extract_gmsh_model("x");
      } catch (...) {
      }
      _exit(0);
    }
    int st = 0;
    waitpid(pid, &st, 0);
    const bool sig = (WIFEXITED(st) && WEXITSTATUS(st) >= 128) || WIFSIGNALED(st);
    if (sig) {
      ++crashes;
      char name[64];
      std::snprintf(name, sizeof name, "crash_%05ld.msh", t);
      std::rename("try.msh", name);
      std::string bt = "bt_" + std::string(name) + ".txt";
      std::rename("bt.txt", bt.c_str());
    }
    if (t % 5000 == 0) std::fprintf(stderr, "%ld tries, %ld crashes\n", t, crashes);
  }
  std::fprintf(stderr, "done: %ld tries, %ld crashes\n", tries, crashes);
  gmsh::finalize();
}
