/* config.h — isomeshd's settings: every flag with its default, `--config FILE` (lines
 * `name = value` using the flag names), and --help. Command-line flags win over the file. */
#ifndef ISMD_CONFIG_H
#define ISMD_CONFIG_H

#include <stdbool.h>
#include <stddef.h>

#include "server/common/log.h"

typedef struct ismd_config {
    char listen_host[256];
    unsigned short listen_port;
    int workers;              /* worker processes (default: online cores) */
    int queue;                /* jobs waiting for a worker before 503 */
    int user_jobs;            /* computations one user may have queued or running (429 beyond) */
    int user_running;         /* computations of one user on workers at once (0 = no limit) */
    bool queue_fifo;          /* --queue-order fifo (the reference); else fair round robin */
    char tokens[4096];        /* bearer tokens file; "" = no access control */
    bool private_mode;        /* --private: reading needs a token too */
    char cache_dir[4096];
    size_t cache_mem;         /* bytes of the in-memory LRU */
    unsigned long long cache_disk_max; /* bytes the disk cache may hold (0 = no bound) */
    double job_timeout_s;     /* deadline of one computation, from its start on a worker */
    double queue_timeout_s;   /* longest wait for a worker (503 queue_timeout beyond) */
    size_t job_memory;        /* RLIMIT_AS of a worker process (0 = unlimited) */
    size_t max_body;          /* request body bytes */
    size_t upload_memory;     /* bytes all request bodies being received may hold at once */
    unsigned conn_timeout_s;  /* an idle connection (not waiting for a computation) is closed */
    int client_conns;         /* connections from one address at once (0 = no limit) */
    unsigned max_conns;       /* connections held at once, fair across addresses (conns.h) */
    double header_timeout_s;  /* a request's headers arrive within this (conns.h) */
    double body_timeout_s;    /* a request's body arrives within this of its headers */
    int http_threads;         /* at least this many HTTP threads (http.c may start more) */
    char tcp_congestion[16];  /* congestion control of accepted sockets; "" = the system's */
    bool own_sender;          /* cached meshes sent by http_front.h (--own-sender) */
    int max_depth;
    size_t max_triangles;
    char web_root[4096];      /* "" = no viewer */
    char data_dir[4096];      /* openapi.yaml, request.schema.json */
    char cors_origin[512];    /* "" = no CORS headers */
    char trusted_proxy[512];  /* addresses (comma-separated) whose X-Real-IP names the
                                 client; "" = the peer address is the client */
    char redis[300];          /* HOST:PORT of the shared cache (shared_cache.h); "" = none */
    double redis_lock_ttl_s;  /* lifetime of a computation's lock in Redis */
    bool cluster;             /* --cluster: one queue in Redis for every daemon (cluster.h) */
    char redis_namespace[64]; /* keys start "<namespace>:v1:"; "" = isomesh */
    char redis_password_file[4096]; /* AUTH with its first line; "" = none */
    ism_log_format log_format;
    char worker_path[4096];   /* the isomesh binary */
} ismd_config;

/* Fills cfg from defaults, then --config FILE, then the flags. Returns 0 to run, 1 when
 * --help or --version printed something (exit 0), 2 on a bad flag or value (a one-line
 * message was printed to stderr). */
int ismd_config_load(ismd_config *cfg, int argc, char **argv);

#endif
