# mk/drm.mk - the viewer's DRM/KMS back end (issue 17: the screen of a board whose kernel has no
# framebuffer device).  platform/cm_drm.c needs only libdrm's headers (Debian's libdrm-dev, also
# :arm64): the kernel's own ioctls, none of libdrm's allocating calls, nothing linked.  Without the
# headers (armhf here) platform/cm_drm_none.c refuses a DRM device by name.
DRM_HEADERS_OK := $(shell $(PKG_CONFIG) --exists libdrm 2>/dev/null && echo 1)
ifeq ($(DRM_HEADERS_OK),1)
DRM_SRC := platform/cm_drm.c
DRM_CFLAGS := $(shell $(PKG_CONFIG) --cflags libdrm)
else
DRM_SRC := platform/cm_drm_none.c
DRM_CFLAGS :=
endif
drm_obj = $(patsubst %.c,$(call bdir,$(1))/%.o,$(DRM_SRC))
$(BUILD_ROOT)/%/platform/cm_drm.o: CPPFLAGS += $(DRM_CFLAGS)
$(foreach p,$(PROFILES),$(eval $(call bdir,$(p))/cmz-view: $(call drm_obj,$(p))))
