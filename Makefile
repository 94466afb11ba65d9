# Tessera's thin Makefile: the two commands of the quick start, and a few
# conveniences. The build itself is CMake's.
BUILD ?= build
ASAN_BUILD ?= build-asan
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
CMAKE_FLAGS ?=
MAKEFLAGS += --no-print-directory

.PHONY: all deps build demo test test-release test-asan format clean fuzz

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
	@cd $(ASAN_BUILD) && ASAN_OPTIONS=detect_leaks=1:halt_on_error=1 \
	  UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
	  LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 \
	  ctest -j $(JOBS) --output-on-failure -E '^triangulate_cli_data$$'

# libFuzzer targets (tests/fuzz): builds them with clang, ASan and UBSan in
# $(FUZZ_BUILD), then runs each for FUZZ_SECONDS, growing a corpus kept in
# $(FUZZ_BUILD)/work/<target> from the seeds in tests/fuzz/corpus/<target>.
# Runs go on past a crash (-fork=1 -ignore_crashes=1); crash inputs land in
# $(FUZZ_BUILD)/artifacts/<target>/ and make the target fail.
FUZZ_BUILD ?= build-fuzz
FUZZ_SECONDS ?= 60
FUZZ_TARGETS ?= pslg_io triangulate heightfield patch_io
fuzz: deps
	@cmake -S . -B $(FUZZ_BUILD) -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ -DCMAKE_BUILD_TYPE=Debug \
	  -DCMAKE_C_FLAGS_DEBUG="-g -O1" -DCMAKE_CXX_FLAGS_DEBUG="-g -O1" -DTSR_WERROR=ON -DTSR_SANITIZE=ON \
	  -DTSR_FUZZ=ON -DBUILD_TESTING=OFF $(CMAKE_FLAGS) >/dev/null
	@cmake --build $(FUZZ_BUILD) -j $(JOBS) --target fuzzers
	@status=0; for t in $(FUZZ_TARGETS); do \
	  art=$(FUZZ_BUILD)/artifacts/$$t; rm -rf $$art $(FUZZ_BUILD)/tmp; \
	  mkdir -p $$art $(FUZZ_BUILD)/work/$$t $(FUZZ_BUILD)/tmp; \
	  echo "fuzz: $$t for $(FUZZ_SECONDS) s (log: $(FUZZ_BUILD)/fuzz-$$t.log)"; \
	  TMPDIR=$(abspath $(FUZZ_BUILD))/tmp $(FUZZ_BUILD)/bin/fuzz_$$t -max_total_time=$(FUZZ_SECONDS) -timeout=10 \
	    -fork=1 -ignore_crashes=1 -artifact_prefix=$$art/ $(FUZZ_BUILD)/work/$$t tests/fuzz/corpus/$$t \
	    > $(FUZZ_BUILD)/fuzz-$$t.log 2>&1 || status=1; \
	  grep -E '^#[0-9]+: ' $(FUZZ_BUILD)/fuzz-$$t.log | tail -n 1; \
	  n=$$(ls $$art | wc -l); \
	  if [ "$$n" -gt 0 ]; then status=1; echo "fuzz: $$t: $$n crash input(s) in $$art:"; ls $$art | sed 's/^/  /'; fi; \
	done; \
	if [ $$status -ne 0 ]; then echo "fuzz: replay one with $(FUZZ_BUILD)/bin/fuzz_<target> FILE"; exit 1; fi

format:
	@clang-format -i $$(git ls-files '*.c' '*.h' '*.cpp')

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) out
