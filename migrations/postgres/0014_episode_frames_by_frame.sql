-- As SQLite's 0022: an episode's frames and thumbnails found by frame.
CREATE INDEX episode_frames_by_frame ON episode_frames (frame);
CREATE INDEX episode_frames_by_thumbnail ON episode_frames (thumbnail);
