// omniloc_top: the board-independent design: encoder core + gyro reader + UART link.
//
// uart_rx -> frame_rx -> link_engine -> frame_tx -> uart_tx; link_engine masters the register
// bus of encoder_core and streams its windows. gyro_ctrl (rtl/gyro/) reads an ICM-42688-P over
// SPI and sums its yaw-rate samples per window, ticked by the core's window tick so that a
// captured window's gyro sum and encoder counts cover the same interval; the core puts them in one
// window bank.
// LINK_ERRORS (UART receive error counters) and GYRO_STATE (the reader's live state) are answered
// here; every other address goes to the core.
// Assumptions: one clock of CLK_HZ; rst_i synchronous, active high; uart_rx_i and the encoder
// pins asynchronous (synchronised inside). CLK_HZ / BAUD >= 4 and should divide exactly
// (docs/RTL.md lists the rates). The defaults are the board's (common/regmap.json "link": 12 MHz,
// 100 Hz windows, 1 Mbaud, 4 channels); every width comes from the generated map. CHANNELS 3 builds a
// three-wheel board (encoder_core): the ports and the window layout stay 4 channels wide.
`resetall
`timescale 1ns / 1ps
`default_nettype none
`include "omniloc_regs.vh"

module omniloc_top #(
    parameter integer CLK_HZ  = `OMNILOC_BOARD_CLOCK_HZ,
    parameter integer TICK_HZ = `OMNILOC_TICK_HZ,
    parameter integer BAUD    = `OMNILOC_UART_BAUD,
    parameter integer CHANNELS = `OMNILOC_CHANNELS   // 3 or 4 wheels (encoder_core); CONFIG.CHANNELS
) (
    input  wire       clk_i,
    input  wire       rst_i,
    input  wire [`OMNILOC_CHANNELS-1:0] enc_a_i,
    input  wire [`OMNILOC_CHANNELS-1:0] enc_b_i,
    input  wire       uart_rx_i,
    output wire       uart_tx_o,
    output wire       spi_sclk_o,   // to the ICM-42688-P (SPI mode 0)
    output wire       spi_mosi_o,
    input  wire       spi_miso_i,
    output wire       spi_cs_n_o,
    output wire       activity_o,   // a byte went either way in the last ~50 ms
    output wire       error_o       // a sticky error: illegal transition, refused write or UART error
);

localparam integer ADDR_W = `OMNILOC_ADDR_W;
localparam integer DATA_W = `OMNILOC_DATA_W;
localparam integer CH     = `OMNILOC_CHANNELS;
localparam integer GSUM_W = `OMNILOC_GYRO_SUM_BITS;
localparam integer GCNT_W = `OMNILOC_GYRO_COUNT_BITS;
localparam integer GFLG_W = `OMNILOC_BODY_WINDOW_GYRO_FLAGS_W;
localparam integer GFCNT_W = `OMNILOC_GYRO_STATE_FAULTS_W;
generate
    if (GSUM_W != 16 + GCNT_W) begin : bad_gyro_widths
        bad_regmap_GYRO_SUM_BITS_must_be_16_plus_GYRO_COUNT_BITS gyro_width_error();
    end
    if (`OMNILOC_GYRO_FLAG_WRONG_ID != 0 || `OMNILOC_GYRO_FLAG_DROPPED != 4) begin : bad_gyro_flags
        bad_regmap_GYRO_FLAG_bits_0_to_4_are_gyro_ctrl_flags gyro_flags_error();
    end
endgenerate

// ---- UART ----
wire [7:0]  rx_byte;
wire        rx_valid, rx_ready;
wire [`OMNILOC_LINK_ERRORS_FRAMING_W-1:0] rx_framing;
wire [`OMNILOC_LINK_ERRORS_OVERRUN_W-1:0] rx_overruns;
uart_rx #(.CLK_HZ(CLK_HZ), .BAUD(BAUD)) u_uart_rx (
    .clk_i(clk_i), .rst_i(rst_i), .rx_i(uart_rx_i),
    .data_o(rx_byte), .valid_o(rx_valid), .ready_i(rx_ready),
    .framing_errors_o(rx_framing), .overruns_o(rx_overruns));

wire [7:0] tx_byte;
wire       tx_valid, tx_ready;
uart_tx #(.CLK_HZ(CLK_HZ), .BAUD(BAUD)) u_uart_tx (
    .clk_i(clk_i), .rst_i(rst_i), .data_i(tx_byte), .valid_i(tx_valid), .ready_o(tx_ready),
    .tx_o(uart_tx_o));

// ---- frames ----
wire              ev_valid, ev_ready, ev_error;
wire [7:0]        ev_code;
wire              ev_read, ev_write;
wire [ADDR_W-1:0] ev_addr;
wire [DATA_W-1:0] ev_data;
frame_rx #(.TIMEOUT_CYCLES(CLK_HZ / 1000 * `OMNILOC_FRAME_GAP_TIMEOUT_US / 1000)) u_frame_rx (
    .clk_i(clk_i), .rst_i(rst_i),
    .byte_i(rx_byte), .byte_valid_i(rx_valid), .byte_ready_o(rx_ready),
    .ev_valid_o(ev_valid), .ev_ready_i(ev_ready), .ev_error_o(ev_error),
    .ev_code_o(ev_code), .ev_read_o(ev_read), .ev_write_o(ev_write), .ev_addr_o(ev_addr), .ev_data_o(ev_data));

localparam integer BODY_BYTES = `OMNILOC_FRAME_TELEMETRY_BODY_BYTES;
wire                    ftx_start, ftx_ready;
wire [7:0]              ftx_type, ftx_len;
localparam integer IDX_W = $clog2(BODY_BYTES + 1);
wire [IDX_W-1:0]        ftx_idx;
wire [7:0]              ftx_byte;
frame_tx #(.MAX_BODY_BYTES(BODY_BYTES)) u_frame_tx (
    .clk_i(clk_i), .rst_i(rst_i),
    .start_i(ftx_start), .ready_o(ftx_ready), .type_i(ftx_type), .body_len_i(ftx_len),
    .body_idx_o(ftx_idx), .body_byte_i(ftx_byte),
    .byte_o(tx_byte), .byte_valid_o(tx_valid), .byte_ready_i(tx_ready));

// ---- gyro: ICM-42688-P reader, its windows ticked by the core's window tick ----
// Every tick, enabled or not: a capture (a tick while CONTROL.ENABLE) then latches the gyro's
// window at the same edge as the encoders', and the first window after ENABLE holds the last
// 10 ms rather than everything since reset (which would overflow the sample count).
wire signed [GSUM_W-1:0] gyro_sum;
wire [GCNT_W-1:0]        gyro_count;
wire [4:0]               gyro_accum_flags;
wire [GFCNT_W-1:0]       gyro_faults;
wire                     gyro_running, gyro_id_fault;
wire                     tick;      // the core's window tick: the gyro's window
gyro_ctrl #(.CLK_HZ(CLK_HZ), .SCLK_HZ(`OMNILOC_GYRO_SCLK_HZ), .ODR_HZ(`OMNILOC_GYRO_ODR_HZ),
            .FS_DPS(`OMNILOC_GYRO_FS_DPS), .COUNT_W(GCNT_W), .FCNT_W(GFCNT_W)) u_gyro (
    .clk_i(clk_i), .rst_i(rst_i), .tick_i(tick),
    .spi_sclk_o(spi_sclk_o), .spi_mosi_o(spi_mosi_o), .spi_miso_i(spi_miso_i), .spi_cs_n_o(spi_cs_n_o),
    .gyro_sum_o(gyro_sum), .gyro_count_o(gyro_count), .gyro_flags_o(gyro_accum_flags),
    /* verilator lint_off PINCONNECTEMPTY */
    .gyro_valid_o(),
    /* verilator lint_on PINCONNECTEMPTY */
    .gyro_fault_count_o(gyro_faults), .gyro_running_o(gyro_running), .gyro_id_fault_o(gyro_id_fault));
// ABSENT: a wrong WHO_AM_I and no successful start-up since. It and NOT_RUNNING are latched at
// the tick, as gyro_accum latches its flags, so the window's flags byte is of one instant.
reg gyro_absent_q, gyro_not_running_q, gyro_absent_win_q;
always @(posedge clk_i) begin
    if (rst_i) begin
        gyro_absent_q <= 1'b0;
        gyro_not_running_q <= 1'b0;
        gyro_absent_win_q <= 1'b0;
    end else begin
        if (gyro_id_fault) gyro_absent_q <= 1'b1;
        else if (gyro_running) gyro_absent_q <= 1'b0;
        if (tick) begin
            gyro_not_running_q <= !gyro_running;
            gyro_absent_win_q <= gyro_absent_q;
        end
    end
end
reg [GFLG_W-1:0] gyro_flags;
always @(*) begin
    gyro_flags = {GFLG_W{1'b0}};
    gyro_flags[4:0] = gyro_accum_flags;   // gyro_ctrl's bits are GYRO_FLAG_WRONG_ID .. _DROPPED
    gyro_flags[`OMNILOC_GYRO_FLAG_NOT_RUNNING] = gyro_not_running_q;
    gyro_flags[`OMNILOC_GYRO_FLAG_ABSENT] = gyro_absent_win_q;
end

// ---- register bus: LINK_ERRORS and GYRO_STATE here, the rest in the core ----
wire [ADDR_W-1:0] bus_addr;
wire              bus_rd, bus_wr;
wire [DATA_W-1:0] bus_wdata;
wire              to_link = (bus_addr == `OMNILOC_REG_LINK_ERRORS) || (bus_addr == `OMNILOC_REG_GYRO_STATE);

wire [DATA_W-1:0] core_rdata;
wire              core_ack, core_err;
reg               link_ack_q, link_err_q;
reg  [DATA_W-1:0] link_rdata_q;
// LINK_ERRORS: the receiver's counters at their fields.
// GYRO_STATE: the reader's live state.
reg  [DATA_W-1:0] link_errors, gyro_state;
always @(*) begin
    link_errors = {DATA_W{1'b0}};
    link_errors[`OMNILOC_LINK_ERRORS_FRAMING_LSB +: `OMNILOC_LINK_ERRORS_FRAMING_W] = rx_framing;
    link_errors[`OMNILOC_LINK_ERRORS_OVERRUN_LSB +: `OMNILOC_LINK_ERRORS_OVERRUN_W] = rx_overruns;
    gyro_state = {DATA_W{1'b0}};
    gyro_state[`OMNILOC_GYRO_STATE_RUNNING_LSB] = gyro_running;
    gyro_state[`OMNILOC_GYRO_STATE_ABSENT_LSB] = gyro_absent_q;
    gyro_state[`OMNILOC_GYRO_STATE_FAULTS_LSB +: GFCNT_W] = gyro_faults;
end
always @(posedge clk_i) begin
    if (rst_i) begin
        link_ack_q   <= 1'b0;
        link_err_q   <= 1'b0;
        link_rdata_q <= {DATA_W{1'b0}};
    end else begin
        link_ack_q   <= to_link && (bus_rd || bus_wr);
        link_err_q   <= bus_wr;                    // read-only
        link_rdata_q <= (bus_addr == `OMNILOC_REG_GYRO_STATE) ? gyro_state : link_errors;
    end
end
wire [DATA_W-1:0] bus_rdata = link_ack_q ? link_rdata_q : core_rdata;
wire        bus_ack   = link_ack_q | core_ack;
wire        bus_err   = link_ack_q ? link_err_q : core_err;

wire                 win_valid, win_consumed, stream_en;
wire [7:0]           bank_byte;
wire [DATA_W-1:0]    win_seq, win_ts;
wire [CH*DATA_W-1:0] win_count, win_position;
wire [CH-1:0]        win_dir;
wire [`OMNILOC_BODY_WINDOW_STATUS_W-1:0] status;   // STATUS at capture, as the window's status byte
encoder_core #(.CLK_HZ(CLK_HZ), .TICK_HZ(TICK_HZ), .CHANNELS(CHANNELS)) u_core (
    .clk_i(clk_i), .rst_i(rst_i), .enc_a_i(enc_a_i), .enc_b_i(enc_b_i),
    .gyro_sum_i(gyro_sum), .gyro_count_i(gyro_count), .gyro_flags_i(gyro_flags),
    .reg_addr_i(bus_addr), .reg_rd_i(bus_rd && !to_link), .reg_wr_i(bus_wr && !to_link),
    .reg_wdata_i(bus_wdata), .reg_rdata_o(core_rdata), .reg_ack_o(core_ack), .reg_err_o(core_err),
    .win_valid_o(win_valid), .win_seq_o(win_seq), .win_timestamp_o(win_ts), .win_count_o(win_count),
    .win_position_o(win_position), .win_dir_o(win_dir), .status_o(status),
    .win_consumed_i(win_consumed), .stream_en_o(stream_en), .tick_o(tick),
    .bank_idx_i(ftx_idx), .bank_byte_o(bank_byte));

link_engine u_link (
    .clk_i(clk_i), .rst_i(rst_i),
    .ev_valid_i(ev_valid), .ev_ready_o(ev_ready), .ev_error_i(ev_error), .ev_code_i(ev_code), .ev_read_i(ev_read), .ev_write_i(ev_write),
    .ev_addr_i(ev_addr), .ev_data_i(ev_data),
    .tx_start_o(ftx_start), .tx_ready_i(ftx_ready), .tx_type_o(ftx_type), .tx_body_len_o(ftx_len),
    .tx_idx_i(ftx_idx), .tx_byte_o(ftx_byte),
    .reg_addr_o(bus_addr), .reg_rd_o(bus_rd), .reg_wr_o(bus_wr), .reg_wdata_o(bus_wdata),
    .reg_rdata_i(bus_rdata), .reg_ack_i(bus_ack), .reg_err_i(bus_err),
    .stream_en_i(stream_en), .win_valid_i(win_valid), .bank_byte_i(bank_byte),
    .win_consumed_o(win_consumed));

// ---- LEDs: activity held for 5 window ticks (~50 ms), errors sticky ----
// Counting ticks rather than clock cycles keeps the counter at 3 bits (no long carry chain).
reg [2:0] activity_q;
always @(posedge clk_i) begin
    if (rst_i) activity_q <= 3'd0;
    else if ((rx_valid && rx_ready) || (tx_valid && tx_ready)) activity_q <= 3'd5;
    else if (tick && activity_q != 3'd0) activity_q <= activity_q - 3'd1;
end
assign activity_o = (activity_q != 3'd0);
assign error_o = (|status[`OMNILOC_STATUS_ILLEGAL_LSB +: `OMNILOC_STATUS_ILLEGAL_W])
               || status[`OMNILOC_STATUS_BAD_WRITE_LSB] || status[`OMNILOC_STATUS_GYRO_FAULT_LSB]
               || (|rx_framing) || (|rx_overruns);

// The live window and positions are for other tops (e.g. a position display); the link sends
// the frozen bank.
wire unused_ok = &{1'b0, win_position, win_seq, win_ts, win_count, win_dir, status};

endmodule

`default_nettype wire
