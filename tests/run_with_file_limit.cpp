// run_with_file_limit BYTES PROGRAM [ARGUMENTS...]: runs PROGRAM as a full disk would meet it.
//
// Sets RLIMIT_FSIZE to BYTES and ignores SIGXFSZ, then execs PROGRAM (both survive the exec): a
// write that would take any file past BYTES fails with EFBIG ("File too large"), as a write to a
// full disk fails with ENOSPC, and the program goes on to see the failure rather than being
// killed by the signal. Unlike a small tmpfs this needs no mount (no root, no CAP_SYS_ADMIN),
// and unlike an LD_PRELOAD shim it fails the real system calls of every library the program uses
// (OpenImageIO, OpenVDB, the C++ streams). Used by cmake/check_output_failures.cmake.

#include <sys/resource.h>

#include <cerrno>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <unistd.h>

int main(int argc, char** argv)
{
    if (argc < 3) {
        std::fprintf(stderr, "usage: run_with_file_limit BYTES PROGRAM [ARGUMENTS...]\n");
        return 125;
    }
    char* end = nullptr;
    const unsigned long long bytes = std::strtoull(argv[1], &end, 10);
    if (end == argv[1] || *end != '\0') {
        std::fprintf(stderr, "run_with_file_limit: '%s' is not a byte count\n", argv[1]);
        return 125;
    }
    const rlimit limit{rlim_t(bytes), rlim_t(bytes)};
    if (setrlimit(RLIMIT_FSIZE, &limit) != 0) {
        std::fprintf(stderr, "run_with_file_limit: setrlimit(RLIMIT_FSIZE, %llu): %s\n", bytes, std::strerror(errno));
        return 125;
    }
    std::signal(SIGXFSZ, SIG_IGN); // an ignored signal stays ignored across exec
    execvp(argv[2], argv + 2);
    std::fprintf(stderr, "run_with_file_limit: cannot run %s: %s\n", argv[2], std::strerror(errno));
    return 126;
}
