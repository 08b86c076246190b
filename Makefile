# gi-farm: one entry point. `make demo` and `make test` work on a fresh
# Debian 12 machine: they install missing packages first (scripts/deps.sh).
#
#   make deps     install missing Debian packages (root or sudo)
#   make all      build release binaries into build/release/
#   make demo     build and render the Cornell box with every method into out/
#   make test     build (release + ASan/UBSan) and run the whole suite
#   make bench    build and run the benchmark drivers (bench/)
#   make fuzz     long fuzzing runs of every fuzz target
#   make install  build and install gi, gi-farmd, gi-worker (only those) into
#                 $(PREFIX)/bin
#
# Public targets call deps, then re-enter make so pkg-config sees the
# packages deps just installed.

PREFIX ?= /usr/local
BUILD  ?= build
OUT    ?= out
JOBS   ?= $(shell nproc 2>/dev/null || echo 2)

.PHONY: all deps demo test check-asan bench fuzz install clean binaries programs
.DEFAULT_GOAL := all

all: deps
	@$(MAKE) --no-print-directory -j$(JOBS) binaries CFG=release

deps:
	@sh scripts/deps.sh

demo: all
	@sh scripts/demo.sh $(BUILD)/release $(OUT)

test: deps
	@$(MAKE) --no-print-directory -j$(JOBS) binaries CFG=release
	@$(MAKE) --no-print-directory -j$(JOBS) binaries CFG=asan
	@$(MAKE) --no-print-directory -j$(JOBS) fuzzers
	@sh tests/run.sh $(BUILD)

check-asan: test

bench: deps
	@$(MAKE) --no-print-directory -j$(JOBS) binaries CFG=release
	@sh bench/run.sh $(BUILD)/release

fuzz: deps
	@$(MAKE) --no-print-directory -j$(JOBS) fuzzers
	@sh tests/fuzz/run.sh $(BUILD)/fuzz long

# The three programs alone: an image or a package needs neither the tests
# nor the tools.
install: deps
	@$(MAKE) --no-print-directory -j$(JOBS) programs CFG=release
	install -d $(DESTDIR)$(PREFIX)/bin
	for p in $(PROGRAMS); do \
	  install -m 755 $(BUILD)/release/$$p $(DESTDIR)$(PREFIX)/bin/ || exit 1; \
	done

clean:
	rm -rf $(BUILD)

# ---------------------------------------------------------------------------
# Build rules (entered with CFG=release or CFG=asan).

CFG ?= release
PKGS = OpenEXR libcjson libpng zlib libdeflate assimp libzstd libsodium libmicrohttpd openblas lapacke
PKG_CFLAGS = $(shell pkg-config --cflags $(PKGS))
PKG_LIBS   = $(shell pkg-config --libs $(PKGS)) -lembree3 -lm

WARN = -Wall -Wextra -Werror -Wshadow -Wstrict-prototypes -Wno-unused-parameter
# -ffp-contract=off: no multiply-add is fused unless the code says so
# (fmaf, intrinsics). Functions built for AVX2/AVX-512 (detp_lanes.c) would
# otherwise round otherwise than the same arithmetic elsewhere, and hosts
# with different CPUs would count different disc crossings.
BASE_CFLAGS = -std=gnu11 -g $(WARN) -I. -Icommon -Iprotocol -Iworker -Iserver \
	      -D_GNU_SOURCE -MMD -MP -ffp-contract=off

ifeq ($(CFG),asan)
OPT_CFLAGS = -O1 -fno-omit-frame-pointer -fsanitize=address,undefined \
	     -fno-sanitize-recover=undefined
OPT_LDFLAGS = -fsanitize=address,undefined
else
OPT_CFLAGS = -O2 -march=x86-64-v2 -fno-math-errno
OPT_LDFLAGS =
endif

CFLAGS_ALL = $(BASE_CFLAGS) $(OPT_CFLAGS) $(PKG_CFLAGS) $(CFLAGS)
LDFLAGS_ALL = $(OPT_LDFLAGS) -Wl,--as-needed $(LDFLAGS)

O := $(BUILD)/$(CFG)

# Library sources: everything in the four component folders except the
# program entry points (*_main.c).
LIB_SRC := $(filter-out %_main.c,$(wildcard common/*.c common/*/*.c protocol/*.c \
	     worker/*.c server/*.c))
LIB_OBJ := $(LIB_SRC:%.c=$(O)/obj/%.o)
LIB     := $(O)/libgi.a

PROGRAMS := gi gi-farmd gi-worker
MAIN_SRC := $(wildcard server/*_main.c worker/*_main.c)
PROG_BIN := $(foreach s,$(MAIN_SRC),$(O)/$(subst _,-,$(patsubst %_main.c,%,$(notdir $(s)))))

TEST_SRC := $(wildcard tests/unit/*.c)
TEST_OBJ := $(TEST_SRC:%.c=$(O)/obj/%.o)
TOOL_SRC := $(wildcard tests/tools/*.c)
TOOL_BIN := $(TOOL_SRC:tests/tools/%.c=$(O)/tools/%)
BENCH_SRC := $(wildcard bench/*.c)
BENCH_BIN := $(BENCH_SRC:bench/%.c=$(O)/bench/%)
# Scene generators (scenes/tools/*.c -> build/<cfg>/scenes/NAME).
SCENE_TOOL_SRC := $(wildcard scenes/tools/*.c)
SCENE_TOOL_BIN := $(SCENE_TOOL_SRC:scenes/tools/%.c=$(O)/scenes/%)

binaries: $(PROG_BIN) $(O)/gi-tests $(TOOL_BIN) $(BENCH_BIN) $(SCENE_TOOL_BIN)
programs: $(PROG_BIN)

Q = $(if $(V),,@)

$(O)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	@$(if $(V),,echo "  CC [$(CFG)] $<")
	$(Q)$(CC) $(CFLAGS_ALL) -c $< -o $@

$(LIB): $(LIB_OBJ)
	@rm -f $@
	$(Q)ar rcs $@ $^

# server/gi_main.c -> gi, server/gi_farmd_main.c -> gi-farmd, ...
define prog_rule
$(O)/$(subst _,-,$(patsubst %_main.c,%,$(notdir $(1)))): $(O)/obj/$(1:.c=.o) $(LIB)
	@$$(if $$(V),,echo "  LD [$$(CFG)] $$@")
	$$(Q)$$(CC) $$(LDFLAGS_ALL) -o $$@ $$^ $$(PKG_LIBS)
endef
$(foreach s,$(MAIN_SRC),$(eval $(call prog_rule,$(s))))

$(O)/gi-tests: $(TEST_OBJ) $(LIB)
	@$(if $(V),,echo "  LD [$(CFG)] $@")
	$(Q)$(CC) $(LDFLAGS_ALL) -o $@ $^ $(PKG_LIBS)

$(O)/tools/%: $(O)/obj/tests/tools/%.o $(LIB)
	@mkdir -p $(dir $@)
	@$(if $(V),,echo "  LD [$(CFG)] $@")
	$(Q)$(CC) $(LDFLAGS_ALL) -o $@ $^ $(PKG_LIBS)

$(O)/scenes/%: $(O)/obj/scenes/tools/%.o $(LIB)
	@mkdir -p $(dir $@)
	@$(if $(V),,echo "  LD [$(CFG)] $@")
	$(Q)$(CC) $(LDFLAGS_ALL) -o $@ $^ $(PKG_LIBS)

$(O)/bench/%: $(O)/obj/bench/%.o $(LIB)
	@mkdir -p $(dir $@)
	@$(if $(V),,echo "  LD [$(CFG)] $@")
	$(Q)$(CC) $(LDFLAGS_ALL) -o $@ $^ $(PKG_LIBS)

# Fuzz targets: clang + libFuzzer + ASan/UBSan, each linked with the library
# sources compiled the same way.
FUZZ_SRC := $(wildcard tests/fuzz/fuzz_*.c)
FO := $(BUILD)/fuzz
FUZZ_CFLAGS = -std=gnu11 -g -O1 -fno-omit-frame-pointer -I. -Icommon -Iprotocol \
	      -Iworker -Iserver -D_GNU_SOURCE -MMD -MP -ffp-contract=off $(WARN) \
	      -Wno-unused-command-line-argument \
	      -fsanitize=fuzzer-no-link,address,undefined -fno-sanitize-recover=undefined $(PKG_CFLAGS)
FUZZ_LIB_OBJ := $(LIB_SRC:%.c=$(FO)/obj/%.o)
FUZZ_BIN := $(FUZZ_SRC:tests/fuzz/%.c=$(FO)/%)

.PHONY: fuzzers
fuzzers: $(FUZZ_BIN)

$(FO)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	@$(if $(V),,echo "  CC [fuzz] $<")
	$(Q)clang $(FUZZ_CFLAGS) -c $< -o $@

$(FO)/libgi.a: $(FUZZ_LIB_OBJ)
	@rm -f $@
	$(Q)ar rcs $@ $^

$(FO)/fuzz_%: $(FO)/obj/tests/fuzz/fuzz_%.o $(FO)/libgi.a
	@$(if $(V),,echo "  LD [fuzz] $@")
	$(Q)clang -fsanitize=fuzzer,address,undefined -o $@ $^ $(PKG_LIBS)

# Keep object files of pattern-built programs (no rebuild on every run).
.SECONDARY:

-include $(shell find $(BUILD) -name '*.d' 2>/dev/null)
