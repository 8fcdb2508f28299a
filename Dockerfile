# syntax=docker/dockerfile:1
# Multi-stage build: compile in the Rust image, run from a slim Debian as a non-root user.
FROM rust:1.95-bookworm AS build
WORKDIR /src
COPY Cargo.toml Cargo.lock ./
COPY crates ./crates
COPY src ./src
COPY migrations ./migrations
COPY templates ./templates
COPY static ./static
COPY locales ./locales
COPY benches ./benches
# The `dist` profile: what is published, with whole-program (fat LTO) optimisation.
RUN cargo build --profile dist --locked --bin enact-hub

FROM debian:bookworm-slim
RUN apt-get update \
 && apt-get install -y --no-install-recommends ca-certificates curl \
 && rm -rf /var/lib/apt/lists/* \
 && useradd --system --uid 10001 --home-dir /data --shell /usr/sbin/nologin enact
COPY --from=build /src/target/dist/enact-hub /usr/local/bin/enact-hub
VOLUME ["/data"]
WORKDIR /data
USER enact
ENV ENACT_HUB_DB=/data/enact-hub.db \
    ENACT_HUB_ADDR=0.0.0.0:8080 \
    RUST_LOG=info
EXPOSE 8080
HEALTHCHECK --interval=30s --timeout=3s --start-period=10s --retries=3 \
  CMD curl -fsS http://127.0.0.1:8080/healthz || exit 1
ENTRYPOINT ["enact-hub"]
CMD ["serve"]
