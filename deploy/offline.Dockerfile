# Offline image (no registry needed): FROM scratch plus a root filesystem that deploy/stage.sh
# assembled on this machine — the @BIN@ binary, the shared libraries it links and the loader.
FROM scratch
COPY rootfs/ /
WORKDIR /
ENTRYPOINT ["/@BIN@"]
