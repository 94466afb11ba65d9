# Tessera's thin Makefile: the two commands of the quick start, and a few
# conveniences. The build itself is CMake's.
BUILD ?= build
ASAN_BUILD ?= build-asan
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
CMAKE_FLAGS ?=
MAKEFLAGS += --no-print-directory

.PHONY: all deps build demo test test-release test-asan format clean

all: build

deps:
	@bash tools/install-deps.sh

build: deps
	@cmake -S . -B $(BUILD) -DCMAKE_BUILD_TYPE=Release -DTSR_WERROR=ON $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(BUILD) -j $(JOBS)

# Installs what is missing, builds (Release), generates the sample terrain
# and meshes it.
demo: build
	@bash tools/demo.sh $(BUILD)/bin/tessera out/demo

# Installs what is missing, builds with -Wall -Wextra -Werror, runs the
# suite, then runs it again under AddressSanitizer + UBSan (all but the
# every-polygon data run of tessera triangulate, too slow instrumented; the
# library's own triangulation tests do run there).
test: test-release test-asan

test-release: build
	@cd $(BUILD) && ctest -j $(JOBS) --output-on-failure

test-asan: deps
	@cmake -S . -B $(ASAN_BUILD) -DCMAKE_BUILD_TYPE=Debug -DTSR_WERROR=ON -DTSR_SANITIZE=ON $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(ASAN_BUILD) -j $(JOBS)
	@cd $(ASAN_BUILD) && ASAN_OPTIONS=detect_leaks=1:halt_on_error=1:fast_unwind_on_malloc=0 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 \
	  ctest -j $(JOBS) --output-on-failure -E '^triangulate_cli_data$$'

format:
	@clang-format -i $$(git ls-files '*.c' '*.h' '*.cpp')

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) out
