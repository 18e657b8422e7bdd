# mk/hw.mk - the terminal's GPIO back end, gpio_probe, and `make check-hw` (the device back ends
# against real kernel drivers in a test VM: tests/hw/).
#
#   make gpio-probe                                   $(B)/tests/platform/gpio_probe (+ _nogpio)
#   make CROSS_COMPILE=aarch64-linux-gnu- gpio-probe  the same for the board (libgpiod-dev:arm64)
#   make gpio-probe-aarch64                           shorthand for the line above
#   make check-hw                                     VM tests (installs the VM's packages as root)
#
# GPIO back end: libgpiod 1.x from 1.6 on (the struct gpiod_line API; libgpiod 2 is another API)
# gives cm_gpio_gpiod.c, anything else cm_gpio_none.c, whose open refuses configured lines.
# The terminal's link rule uses GPIO_SRC / GPIO_CFLAGS / GPIO_LIBS, or $(call gpio_obj,PROFILE).
# Ordinary `make` needs none of the VM's packages: they are installed by check-hw only.

GPIO_LIBGPIOD_OK := $(shell $(PKG_CONFIG) --atleast-version=1.6 libgpiod 2>/dev/null && \
	! $(PKG_CONFIG) --atleast-version=2 libgpiod 2>/dev/null && echo 1)
ifeq ($(GPIO_LIBGPIOD_OK),1)
GPIO_SRC := platform/cm_gpio_gpiod.c
GPIO_CFLAGS := $(shell $(PKG_CONFIG) --cflags libgpiod)
GPIO_LIBS := $(shell $(PKG_CONFIG) --libs libgpiod)
else
GPIO_SRC := platform/cm_gpio_none.c
GPIO_CFLAGS :=
GPIO_LIBS :=
# once per top-level make (not again in each recursive one), and not for clean/deps
ifeq ($(MAKELEVEL),0)
ifneq ($(if $(MAKECMDGOALS),$(filter-out clean deps,$(MAKECMDGOALS)),all),)
GPIO_FOUND := $(shell $(PKG_CONFIG) --modversion libgpiod 2>/dev/null)
GPIO_DEB_ARCH := $(patsubst aarch64-%,:arm64,$(patsubst arm-%-gnueabihf,:armhf,$(filter-out x86_64-%,$(TRIPLET))))
$(info note: GPIO support off: $(if $(GPIO_FOUND),libgpiod $(GPIO_FOUND) is not 1.x >= 1.6,libgpiod 1.6 not found by \
	$(PKG_CONFIG)) (Debian: apt-get install libgpiod-dev$(GPIO_DEB_ARCH)); the terminal will refuse GPIO lines)
endif
endif
endif
# objects of the GPIO back end for a profile: $(call gpio_obj,terminal)
gpio_obj = $(patsubst %.c,$(call bdir,$(1))/%.o,$(GPIO_SRC))
# libgpiod's include path (empty on Debian) for the one file that includes <gpiod.h>
$(BUILD_ROOT)/%/platform/cm_gpio_gpiod.o: CPPFLAGS += $(GPIO_CFLAGS)

GPIO_PROBE := $(B)/tests/platform/gpio_probe
GPIO_PROBE_NOGPIO := $(B)/tests/platform/gpio_probe_nogpio
$(GPIO_PROBE): $(B)/tests/platform/gpio_probe.o $(call gpio_obj,$(PROFILE))
	$(call say,LD      ,$@)
	$(Q)$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^ $(GPIO_LIBS)
# always linked with cm_gpio_none.c: check-hw checks that back end's refusal on the host
$(GPIO_PROBE_NOGPIO): $(B)/tests/platform/gpio_probe.o $(B)/platform/cm_gpio_none.o
	$(call say,LD      ,$@)
	$(Q)$(CC) $(CFLAGS) $(LDFLAGS) -o $@ $^

.PHONY: gpio-probe gpio-probe-aarch64 check-hw
gpio-probe: $(GPIO_PROBE) $(GPIO_PROBE_NOGPIO)

# the board's build: needs gcc-aarch64-linux-gnu, pkgconf:arm64 and libgpiod-dev:arm64 (without the
# last it builds, but with cm_gpio_none.c: the note above says so).  Runs only on an arm64 kernel:
# qemu-user has no GPIO ioctls.
gpio-probe-aarch64:
	$(Q)$(MAKE) --no-print-directory CROSS_COMPILE=aarch64-linux-gnu- CC=aarch64-linux-gnu-gcc \
		AR=aarch64-linux-gnu-ar PKG_CONFIG=aarch64-linux-gnu-pkg-config gpio-probe

# Other fragments hook their VM tests (tests/hw/vm-NAME.sh, run by the same single boot) in with
#   HW_TEST_DEPS += what the script needs built      HW_TEST_ENV += HW_NAME=path (seen in the VM)
# Both are used only in the recipe, so a fragment included after this one may still add to them.
HW_TEST_DEPS ?=
HW_TEST_ENV ?=
check-hw:
	$(Q)$(MAKE) --no-print-directory -s $(GPIO_PROBE) $(GPIO_PROBE_NOGPIO) $(HW_TEST_DEPS)
	$(Q)HW_GPIO_PROBE=$(GPIO_PROBE) HW_GPIO_PROBE_NONE=$(GPIO_PROBE_NOGPIO) $(HW_TEST_ENV) tests/hw/run-hw-tests.sh
